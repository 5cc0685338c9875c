"""``skydome cache``: the on-disk cache of the precomputed model's tables."""

from __future__ import annotations

import typer

from skydome.cli._kit import _run

cache_app = typer.Typer(no_args_is_help=True,
                        help="The on-disk cache of the precomputed model's tables.")

@cache_app.command("info")
def cache_info():
    """Where the cache is, its entries, their total size and the size limit."""
    from skydome.models.simulated.precomputed import _cache

    entries = _cache._entries(_cache.cache_dir())
    total = sum(size for _, size, _ in entries)
    typer.echo(f"folder   {_cache.cache_dir()}")
    typer.echo(f"entries  {len(entries)} table sets, {total / 2**20:.1f} MiB")
    typer.echo(f"limit    {_run(_cache.limit_bytes) / 2**20:.0f} MiB "
               "(SKYDOME_CACHE_LIMIT_BYTES; least recently used sets go first)")


@cache_app.command("clear")
def cache_clear():
    """Remove every cached table set (the next run precomputes again)."""
    from skydome.models.simulated.precomputed import clear_cache

    freed = _run(clear_cache)
    typer.echo(f"cleared {freed / 2**20:.1f} MiB")

