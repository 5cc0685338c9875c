"""The models' capabilities (skydome.models, "Capabilities"): every registered model declares
coherent ones, and the viewer, the LUT bake, the airlight effect and the ground of renders
take their model sets from them, so that a new model appears in each without any list
being edited (a model registered here shows up in all four and is removed afterwards)."""

from pathlib import Path

import numpy as np
import pytest

import skydome as sd
from skydome.models import (OWN_GROUND, TURBIDITY, Parameter, SkyModel, available,
                            check_capabilities, register, unregister)

SHADERS = Path(sd.__file__).parent / "viewer" / "static" / "shaders"


@pytest.mark.parametrize("name", list(available()))
def test_every_model_declares_coherent_capabilities(name):
    from skydome.export.luts import LUT_LAYOUTS
    from skydome.viewer.scene import _BUILDERS

    cls = available()[name]
    check_capabilities(cls)
    declared = {p.name for p in cls.parameters}
    if cls.viewer_shader is not None:
        # the shader exists in the page and the scene has a builder for its numbers
        assert (SHADERS / f"{cls.viewer_shader}.glsl").is_file()
        assert cls.viewer_shader in _BUILDERS
        assert set(cls.viewer_parameters) <= declared
    else:
        assert cls.viewer_parameters == ()
    assert cls.lut_layout is None or cls.lut_layout in LUT_LAYOUTS
    if cls.airlight:
        assert callable(getattr(cls, "aerial_perspective", None)) and "turbidity" in declared
    else:
        assert not cls.airlight_options
    assert cls.own_ground in OWN_GROUND


def test_the_consumers_read_the_capabilities():
    from skydome.effects.airlight import EFFECT_METHODS, METHODS, methods
    from skydome.export.luts import LUT_MODELS, lut_models
    from skydome.imaging.ground import SUN_ONLY_GROUND, sun_only_ground
    from skydome.viewer.scene import VIEWER_MODELS, VIEWS, viewer_models

    models = available()
    assert set(viewer_models()) == ({n for n, c in models.items() if c.viewer_shader}
                                     | set(VIEWS))
    assert set(lut_models()) == {n for n, c in models.items() if c.lut_layout}
    assert set(methods()) == {n for n, c in models.items() if c.airlight} | set(EFFECT_METHODS)
    assert set(sun_only_ground()) == {n for n, c in models.items() if c.own_ground == "sun"}
    # the module constants are the same sets, read when asked for
    assert VIEWER_MODELS == viewer_models() and LUT_MODELS == lut_models()
    assert METHODS == methods() and SUN_ONLY_GROUND == sun_only_ground()
    # the lists that capabilities replaced are all there (a new model may add to them), in
    # the viewer in their order (its page lists the models so and opens on the first)
    old_viewer = ["preetham1999", "hoffman_preetham2002", "oneil2005", "hillaire2020",
                  "precomputed", "dobashi2002"]
    assert [n for n in VIEWER_MODELS if n in old_viewer] == old_viewer
    assert list(VIEWER_MODELS)[0] == "preetham1999" and list(VIEWER_MODELS)[-1] == "dobashi2002"
    assert {"precomputed", "hillaire2020"} <= set(LUT_MODELS)
    assert LUT_MODELS[0] == "precomputed" and METHODS[0] == "precomputed"    # the defaults
    assert {"precomputed", "hillaire2020", "preetham1999", "hoffman_preetham2002",
            "dobashi2002"} <= set(METHODS)
    assert {"single_scattering", "hillaire2020"} <= set(SUN_ONLY_GROUND)


class _Newcomer(SkyModel):
    """A model made for this test: a uniform sky of radiance 1 (every wavelength) and a
    ground of radiance 2, declaring every capability."""

    name = "capability_newcomer_test"
    reference = "none (a test model)"
    native = "spectral"
    parameters = (TURBIDITY, Parameter("level", "", 1.0, 0.0, 10.0, "sky radiance"))
    viewer_shader = "preetham1999"
    viewer_parameters = ("turbidity",)
    lut_layout = "hillaire"
    airlight = True
    own_ground = "sun"

    def radiance(self, directions, wavelengths_nm):
        d = self._directions(directions)
        wl = np.asarray(wavelengths_nm, dtype=np.float64)
        v = np.where(d[..., 2] >= 0.0, self.level, 2.0)
        return np.broadcast_to(v[..., None], d.shape[:-1] + wl.shape).copy()

    def aerial_perspective(self, directions, distance_m, wavelengths_nm):
        d, dist, wl, shape = self._aerial_inputs(directions, distance_m, wavelengths_nm)
        t = np.ones((dist.size, wl.size))
        return self._aerial_outputs(t, 0.0 * t, shape)


@pytest.fixture
def newcomer():
    register(_Newcomer)
    try:
        yield _Newcomer
    finally:
        unregister(_Newcomer.name)
    assert _Newcomer.name not in available()


def test_a_new_model_appears_in_every_consumer(newcomer):
    from skydome.effects.airlight import METHODS, apply_airlight
    from skydome.export.luts import LUT_MODELS
    from skydome.imaging.ground import SUN_ONLY_GROUND, apply_ground
    from skydome.viewer.scene import VIEWER_MODELS, parse_request

    name = newcomer.name
    assert VIEWER_MODELS[name] == ("turbidity",)
    assert name in LUT_MODELS and name in METHODS and name in SUN_ONLY_GROUND
    # the viewer takes a request for it, with the parameters it exposes only
    assert parse_request({"model": name, "turbidity": "3"})[0] == name
    with pytest.raises(ValueError, match="unknown parameter 'level'"):
        parse_request({"model": name, "level": "3"})
    # airlight runs its aerial perspective: transmittance 1 and no in-scattering leave
    # the image as it is with white_balance "sun" (a white surface facing the sun)
    sun = sd.Sun(elevation_deg=30.0, azimuth_deg=180.0)
    img = np.full((2, 2, 3), 0.4)
    out = apply_airlight(img, np.full((2, 2), 500.0), sun, method=name, white_balance="sun",
                         n_wavelengths=5)
    np.testing.assert_allclose(out, img, rtol=1e-9)
    # its own ground lit by the sun only: the render adds the skylight rho E_sky / pi, here
    # with rho = 0.2 (no atmosphere) and E_sky = pi x 1 (a uniform sky of radiance 1)
    sky = newcomer(sun=sun)
    d = np.array([[[0.0, 0.0, -1.0]]])
    data = np.full((1, 1, 2), 2.0)
    apply_ground(sky, data, d, np.ones((1, 1), bool), np.array([500.0, 600.0]), "model")
    np.testing.assert_allclose(data, 2.0 + 0.2 * 1.0, rtol=1e-6)
    assert sky.own_ground in OWN_GROUND


def test_a_model_without_capabilities_appears_in_none():
    from skydome.effects.airlight import METHODS
    from skydome.export.luts import LUT_MODELS
    from skydome.imaging.ground import SUN_ONLY_GROUND
    from skydome.viewer.scene import VIEWER_MODELS

    class Plain(_Newcomer):
        name = "capability_plain_test"
        viewer_shader = None
        viewer_parameters = ()
        lut_layout = None
        airlight = False
        own_ground = None

    register(Plain)
    try:
        assert Plain.name in available()
        for consumer in (VIEWER_MODELS, LUT_MODELS, METHODS, SUN_ONLY_GROUND):
            assert Plain.name not in consumer
    finally:
        unregister(Plain.name)


@pytest.mark.parametrize("attrs, message", [
    ({"viewer_parameters": ("albedo",)}, "viewer_parameters = .* does not declare"),
    ({"viewer_shader": None}, "without a viewer_shader"),
    ({"viewer_shader": "no such/shader"}, "viewer_shader = 'no such/shader'"),
    ({"airlight": "yes"}, "airlight = 'yes' is not True or False"),
    ({"aerial_perspective": None}, "needs an aerial_perspective method"),
    ({"parameters": (Parameter("level", "", 1.0, 0.0, 10.0),), "viewer_parameters": ()},
     "needs an aerial_perspective method and a turbidity parameter"),
    ({"airlight": False}, "airlight_options = .* without airlight = True"),
    ({"own_ground": "moon"}, "own_ground = 'moon' is not one of"),
    ({"lut_layout": 3}, "lut_layout = 3"),
])
def test_incoherent_capabilities_are_refused(attrs, message):
    attrs = {"name": "capability_bad_test", **attrs}
    if "airlight_options" not in attrs and attrs.get("airlight") is False:
        attrs["airlight_options"] = {"use_volume": False}
    bad = type("Bad", (_Newcomer,), attrs)
    with pytest.raises(ValueError, match=message):
        register(bad)
    assert "capability_bad_test" not in available()


def test_unregister_unknown_model():
    with pytest.raises(KeyError, match="not registered"):
        unregister("capability_nosuch_test")


# models cheap enough to build here (the others take seconds to minutes to precompute);
# the parameters the luminance-only ones need (a clear sky of Perez 1993's bins)
_CHEAP = {"cie1994_clear": {}, "cie1994_overcast": {}, "cie2003": {}, "hosek_wilkie2012": {},
          "preetham1999": {}, "hoffman_preetham2002": {}, "oneil2005": {},
          "single_scattering": {}, "klassen1987": {},
          "perez1993": {"epsilon": 4.0, "delta": 0.2}}


@pytest.mark.parametrize("name", sorted(_CHEAP))
def test_own_ground_matches_what_the_model_returns_below_the_horizon(name):
    """``own_ground`` None: nothing below the horizon (0 at the nadir and 30 deg below);
    otherwise a ground of positive radiance there."""
    cls = available()[name]
    sky = cls(sun=sd.Sun(elevation_deg=40.0, azimuth_deg=180.0), **_CHEAP[name])
    d = np.array([[0.0, 0.0, -1.0], [0.0, np.cos(np.radians(30.0)), -0.5]])
    Y = np.asarray(sky.xyz(d))[..., 1]
    if cls.own_ground is None:
        assert np.all(Y == 0.0)
    else:
        assert np.all(Y > 0.0)
