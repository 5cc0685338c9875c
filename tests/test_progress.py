"""The progress protocol of skydome._progress: a no-op by default, routed to a reporter
inside `reporting`, and called by the models whose set-up takes long."""

import threading

import numpy as np
import pytest

import skydome as sd
from skydome._progress import no_progress, report, reporting


def test_default_is_a_no_op_and_reporting_routes_and_restores():
    report("nothing listens", 1, 2)            # must not raise
    seen = []
    with reporting(lambda *a: seen.append(a)):
        report("stage", 1, 3)
        with reporting(None):
            report("silenced", 1, 1)
        report("stage", 3, 3)
    report("after", 1, 1)
    assert seen == [("stage", 1, 3), ("stage", 3, 3)]
    with pytest.raises(TypeError, match="callback"):
        with reporting(42):
            pass
    assert no_progress("x", 0, 1) is None


def test_reporters_do_not_leak_across_threads():
    seen = []

    def other():
        report("other thread", 1, 1)
    with reporting(lambda *a: seen.append(a)):
        t = threading.Thread(target=other)
        t.start()
        t.join()
    assert seen == []


def _monotonic_per_stage(calls):
    stages = {}
    for stage, done, total in calls:
        assert 0 <= done <= total
        stages.setdefault(stage, []).append((done, total))
    for pairs in stages.values():
        assert [d for d, _ in pairs] == sorted(d for d, _ in pairs)
        assert pairs[-1][0] == pairs[-1][1]       # each stage reaches its total
    return stages


def test_dobashi1995_reports_its_table_build():
    calls = []
    sky = sd.model("dobashi1995", sun=sd.Sun(elevation_deg=40, azimuth_deg=0), base="preetham1999",
                   sun_altitudes=4, rings=9, azimuth_samples=8)
    with reporting(lambda *a: calls.append(a)):
        sky.radiance(np.array([[0.0, 0.0, 1.0]]), np.array([450.0, 550.0]))
    stages = _monotonic_per_stage(calls)
    assert list(stages) == ["dobashi1995: sky table"]
    assert stages["dobashi1995: sky table"][-1] == (4, 4)   # one step per precomputed sun altitude


def test_precomputed_reports_each_scattering_order():
    calls = []
    small = dict(n_wavelengths=2, orders=3, transmittance_mu_size=16, transmittance_r_size=8,
                 scattering_r_size=4, scattering_mu_size=8, scattering_mu_s_size=4,
                 scattering_nu_size=2, irradiance_mu_s_size=8, irradiance_r_size=4,
                 integration_samples=4, sphere_samples=4)
    with reporting(lambda *a: calls.append(a)):
        sd.model("precomputed", sun=sd.Sun(elevation_deg=30, azimuth_deg=0), **small)
    stages = _monotonic_per_stage(calls)
    assert [d for d, _ in stages["precomputing tables: scattering orders"]] == [1, 2, 3]
