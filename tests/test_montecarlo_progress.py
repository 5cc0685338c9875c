"""Long Monte Carlo runs report their progress (skydome._progress) block by block, and the
blocks do not change the numbers (each direction and wavelength keeps its random stream)."""

from __future__ import annotations

import numpy as np

import skydome as sd
from skydome._progress import reporting
from skydome.models.simulated import montecarlo as mc


def test_progress_reported_and_result_independent_of_blocks(monkeypatch):
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
    dirs = np.array([[0.0, 0.0, 1.0], [0.5, 0.0, 0.866], [0.0, -0.7, 0.714],
                     [0.9, 0.1, 0.424], [-0.3, 0.3, 0.906]])
    dirs /= np.linalg.norm(dirs, axis=1, keepdims=True)
    wl = np.array([450.0, 550.0])
    one = sd.model("montecarlo", sun=sun, samples=64, seed=3).radiance(dirs, wl)
    assert len(mc._progress_blocks(5, 2, 64)) == 2  # 640 paths: one block
    monkeypatch.setattr(mc, "PROGRESS_PATHS_PER_BLOCK", 100)
    assert mc._progress_blocks(5, 2, 64).tolist() == [0, 1, 2, 3, 4, 5]
    calls = []
    with reporting(lambda stage, done, total: calls.append((stage, done, total))):
        blocks = sd.model("montecarlo", sun=sun, samples=64, seed=3).radiance(dirs, wl)
    np.testing.assert_array_equal(blocks, one)
    assert [c[0] for c in calls] == ["montecarlo paths"] * 5
    assert [c[1] for c in calls] == [128, 256, 384, 512, 640]
    assert all(c[2] == 640 for c in calls)


def test_blocks_bounded_for_a_long_run():
    """polarisation --method montecarlo --samples 1e8 on a 48 x 48 map: at most 200 blocks."""
    b = mc._progress_blocks(48 * 48, 1, 100_000_000)
    assert b[0] == 0 and b[-1] == 48 * 48 and len(b) == mc.PROGRESS_BLOCKS + 1
    assert np.all(np.diff(b) >= 1)
