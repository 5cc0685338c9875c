"""Sky matrices of models with a sun range: twilight hours of a weather file (lit, with the
sun just below the horizon at the hour's midpoint) are left 0 with one note, instead of
stopping the whole matrix at the first of them."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from skydome.daylighting.skymatrix import SunRangeNote, weather_model_sky_matrix
from skydome.daylighting.weather import read_weather, sample_weather_path


@pytest.fixture(scope="module")
def first_twilight_day():
    w = read_weather(sample_weather_path())
    el = 90.0 - w.sun_zenith_deg
    lit = (w.dni + w.dhi) > 1e-4
    k = int(np.argmax(lit & (el < 0.0)))  # the hour the report stopped at (-0.97 deg)
    d0 = k // 24 * 24
    return w.select(slice(d0, d0 + 24))


@pytest.mark.parametrize("model", ["preetham1999", "cie2003"])
def test_twilight_hours_are_zero_rows_with_one_note(first_twilight_day, model):
    w = first_twilight_day
    el = 90.0 - w.sun_zenith_deg
    lit = (w.dni + w.dhi) > 1e-4
    outside = lit & (el < 0.0)
    assert outside.sum() == 2 and el[outside].min() < -3.0  # Greensboro TMY3, 1 January
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        m = weather_model_sky_matrix(w, model, components="luminance", order=1)
    notes = [r for r in rec if issubclass(r.category, SunRangeNote)]
    assert len(notes) == 1
    assert f"model {model!r} covers sun elevations [0, 90] deg: 2 lit hour(s)" in str(
        notes[0].message)
    rows = np.asarray(m).reshape(len(w), -1).max(axis=1)
    assert np.all(rows[outside] == 0.0)
    assert np.all(rows[~lit] == 0.0)
    assert np.all(rows[lit & ~outside] > 0.0)


def test_model_covering_twilight_gets_no_note(first_twilight_day):
    """cie1994_overcast declares [-90, 90] (black below -0.82 deg by its own rule)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", SunRangeNote)
        m = weather_model_sky_matrix(first_twilight_day, "cie1994_overcast",
                                     components="luminance", order=1)
    assert np.all(np.isfinite(np.asarray(m)))
