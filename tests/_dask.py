"""Helper of the Dask tests: one CLI command run in process and again through --scheduler
(the address of a LocalCluster with an in-process worker)."""

from __future__ import annotations


def run_both(args, out_a, out_b):
    """Run ``skydome ARGS --out OUT_A``, then ``... --out OUT_B --scheduler ADDRESS``; assert
    both succeed; return the second run's output."""
    from distributed import LocalCluster
    from typer.testing import CliRunner

    from skydome.cli import app

    args = [str(a) for a in args]
    res = CliRunner().invoke(app, args + ["--out", str(out_a)])
    assert res.exit_code == 0, res.output
    cluster = LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                           dashboard_address=None)
    try:
        res = CliRunner().invoke(app, args + ["--out", str(out_b), "--scheduler",
                                              cluster.scheduler_address])
    finally:
        cluster.close()
    assert res.exit_code == 0, res.output
    return res.output
