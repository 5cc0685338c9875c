"""``python -m skydome.cli``: the typer command line (without the sky-matrix fast path)."""

from skydome.cli.root import main

main()
