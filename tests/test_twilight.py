"""Twilight (survey 5.2) with the precomputed multiple-scattering sky."""

import numpy as np
import pytest
from typer.testing import CliRunner

from skydome.cli import app
from skydome.effects.twilight import (anti_solar_profile, belt_of_venus, horizontal_illuminance,
                                      twilight_models)

SMALL = dict(scattering_r_size=16, scattering_mu_size=64, scattering_mu_s_size=16, orders=3,
             n_wavelengths=10)


@pytest.fixture(scope="module")
def skies():
    deps = [0.0, 2.0, 4.0, 6.0, 9.0, 12.0, 15.0, 18.0, 19.0]
    return deps, twilight_models("precomputed", deps, **SMALL)


def test_zenith_luminance_falls_monotonically_by_four_orders(skies):
    """The zenith dims monotonically with depression, by more than 10^4 from 0 to -12 deg;
    below -18 deg the model's night level is 0 (airglow and starlight not modelled)."""
    deps, sk = skies
    wl = np.linspace(400, 700, 10)
    from skydome.spectra import spectrum_to_xyz

    z = np.array([spectrum_to_xyz(s.radiance(np.array([0, 0, 1.0]), wl), wl)[1] for s in sk])
    assert np.all(np.diff(z[:-1]) < 0)
    assert z[deps.index(0.0)] / z[deps.index(12.0)] > 1e4
    assert z[-1] == 0.0


def test_illuminance_order_of_magnitude_at_end_of_civil_twilight(skies):
    """Horizontal illuminance at sun -6 deg: of order 1-10 lx (about 3 lx is the usual
    figure for the end of civil twilight); the model gives 5-6 lx with the default tables."""
    deps, sk = skies
    e6 = horizontal_illuminance(sk[deps.index(6.0)], np.linspace(400, 700, 10), n_mu=40, n_phi=24)
    assert 1.0 < e6 < 20.0


def test_belt_of_venus_above_earth_shadow(skies):
    """Sun 2 deg below the horizon: opposite the sun, a redder band (the Belt of Venus,
    maximum R/B) lies above a bluer band near the horizon (the earth's shadow)."""
    deps, sk = skies
    el = np.arange(0.5, 30.0, 0.5)
    _, rb = anti_solar_profile(sk[deps.index(2.0)], el, np.linspace(400, 700, 10))
    b = belt_of_venus(el, rb)
    assert 3.0 < b["belt_deg"] < 15.0
    assert b["contrast"] > 0.1


def test_cli_twilight(tmp_path):
    out = tmp_path / "tw"
    res = CliRunner().invoke(app, ["twilight", "--step", "9", "--size", "24", "--wavelengths", "6",
                                   "--scattering-r-size", "8", "--scattering-mu-size", "32",
                                   "--scattering-mu-s-size", "8", "--orders", "2", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert (out / "twilight.csv").exists() and (out / "contact_sheet.png").exists()
    assert "sun  -9.00 deg" in res.output
    res = CliRunner().invoke(app, ["twilight", "--step", "20", "--out", str(tmp_path / "x")])
    assert res.exit_code == 2 and "step = 20" in res.output
