"""The model protocol and the registry of every sky model.

A model is a small class deriving from :class:`SkyModel`. It declares

* ``name``: author+year identifier (``"preetham1999"``), the registry key;
* ``reference``: the citation;
* ``native``: ``"spectral"``, ``"xyz"`` or ``"luminance"``, the quantity it computes;
* ``parameters``: a tuple of :class:`Parameter` (name, unit, default, valid range, meaning);
  shared ones come from here (:data:`ATMOSPHERE`, :data:`TURBIDITY`,
  :data:`OBSERVER_ALTITUDE_M`, :data:`ATMOSPHERE_PARAMETERS`) so each has one range, and
  one description: a line ``{atmosphere_parameters}`` in the class docstring becomes their
  numpydoc entries (:func:`fill_parameter_docs`, run by :func:`register`);
* ``sun_elevation_range_deg`` and ``sun_outside_range``: the sun elevations where it applies
  and what happens outside them (``"raise"`` or ``"black"``; a model that extends itself to
  every elevation, twilight included, declares [-90, 90]);

and implements the native method: ``radiance(directions, wavelengths_nm)`` (spectral,
W m^-2 sr^-1 nm^-1, wavelength axis last), ``xyz(directions)`` (CIE XYZ with Y in cd m^-2)
or ``luminance(directions)`` (cd m^-2). The base class derives the others where that is
physically meaningful. Directions are unit vectors (..., 3) in the East-North-Up frame and
name the direction the light arrives *from*; complex or non-numeric directions are refused
for every model by the base class.

Construction
------------
``SkyModel.__init__(sun, **params)`` does the common work once: ``sun`` must be a
:class:`skydome.Sun`; every keyword must be declared (TypeError listing the valid ones) and
valid (:meth:`Parameter.validate`: floats, ints, choices and strict booleans, each error
naming the parameter, its value and its range); the sun must lie in
``sun_elevation_range_deg`` (ValueError naming ``sun.elevation_deg``, the model and the
range) unless the model is declared black outside it (then ``self._black`` is True); the
atmosphere is resolved where the model declares ``atmosphere`` and ``turbidity``. It then
calls the model's own ``_setup(p, given)`` with the validated parameters. Models whose
constructor takes more than the sun and keywords call ``self._begin(sun, params)``.

The sun
-------
``sun_radiance(wavelengths_nm)`` [W m^-2 sr^-1 nm^-1] (spectral models; None without a
sun), ``sun_luminance()`` [cd m^-2] (every model; None without a sun: luminance-only models
such as ``perez1993``, ``asrc_cie`` and the CIE skies given ``dni_illuminance`` return the
disc's mean luminance, spectral models derive it from ``sun_radiance``) and
``direct_normal_illuminance()`` [lx]. A renderer draws the disc of a luminance-only model
with ``sun_luminance()`` over ``sun.solid_angle_sr`` (D65 chromaticity, as the sky);
:mod:`skydome.illuminance` uses ``direct_normal_illuminance()``.

Aerial perspective
------------------
Models that have it implement one signature, ``aerial_perspective(directions, distance_m,
wavelengths_nm, ...) -> (transmittance, in-scattered radiance)``, both of shape
(..., n_wavelengths); model-specific options follow as keywords. A model whose eye is on
the ground inherits it from :class:`GroundEyeAerialPerspective` and implements only the
rays (``_aerial_rays``).

Capabilities
------------
What the rest of skydome may do with a model is declared on its class, never listed by
name elsewhere; the consumers read these attributes through the registry
(:func:`available`), so a new model that declares them appears in each of them by itself:

* ``viewer_shader`` (None): the WebGL shader that draws the model in the viewer
  (``viewer/static/shaders/<viewer_shader>.glsl``, its uniforms set by ``sky.js`` and
  computed by the builder of that name in :mod:`skydome.viewer.scene`); None: the viewer
  does not offer the model. ``viewer_parameters`` (()): the model parameters its page
  exposes.
* ``lut_layout`` (None): the texture layout of the model's LUT bake for real-time
  renderers (:mod:`skydome.export.luts`: ``"bruneton"`` or ``"hillaire"``); None: no bake.
* ``airlight`` (False): :mod:`skydome.effects.airlight` may use the model's
  ``aerial_perspective`` (the model must have one and take ``turbidity``);
  ``airlight_options`` ({}): the keywords it passes to ``aerial_perspective`` there.
* ``own_ground`` (None): what the model returns below the horizon: None, nothing (renders
  put a Lambertian ground of the model's albedo there, :mod:`skydome.imaging.ground`);
  ``"sun_and_sky"``, its own ground-hit rays, the ground lit by its sun and sky; ``"sun"``,
  its own ground lit by the transmitted sun only (renders add the skylight's share for an
  observer on the ground); ``"own"``, its own ground lit by rules of its own (neither
  of those), which renders keep as they are.

:func:`register` refuses a class whose capabilities are incoherent (a viewer parameter the
model does not declare, airlight without ``aerial_perspective`` or ``turbidity``, an
unknown ``own_ground``).

Models register themselves with :func:`register`; the registry discovers every module in
``skydome.models.analytic``, ``skydome.models.simulated`` and ``skydome.models.fitted`` on
first use, so adding a model needs no edit here. Model modules must not import numba at
module level.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import pkgutil
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any, ClassVar, Mapping

import numpy as np

from skydome._validate import as_directions, check_choice, check_int, check_number, check_real

__all__ = ["Parameter", "SkyModel", "register", "model", "available", "get_model_class", "check_sun",
           "check_capabilities", "unregister", "OWN_GROUND",
           "resolve_atmosphere", "ATMOSPHERE", "TURBIDITY", "OBSERVER_ALTITUDE_M",
           "ATMOSPHERE_PARAMETERS", "ATMOSPHERE_PARAMETERS_DOC", "fill_parameter_docs",
           "GroundEyeAerialPerspective"]


class ParameterTypeError(TypeError, ValueError):
    """A parameter of the wrong type (e.g. ``"yes"`` for a boolean). A TypeError; also a
    ValueError, which some models raised for bad booleans before the protocol was
    enforced in one place."""


@dataclass(frozen=True)
class Parameter:
    """Description of one model parameter.

    Attributes
    ----------
    name : str
        Keyword accepted by the model's constructor.
    unit : str
        Unit of the value ("" for dimensionless).
    default : Any
        Default value (None: required or derived).
    low, high : float or None
        Inclusive valid range for numbers (None: unbounded).
    doc : str
        One line of meaning.
    kind : str
        "float", "int", "choice", "bool" (True or False only, strictly) or "object"
        (validated by the model itself).
    choices : tuple
        Allowed values for kind "choice".
    low_open : bool
        True where ``low`` itself is excluded (a range "(low, high]").
    """

    name: str
    unit: str = ""
    default: Any = None
    low: float | None = None
    high: float | None = None
    doc: str = ""
    kind: str = "float"
    choices: tuple = field(default_factory=tuple)
    low_open: bool = False

    def validate(self, value: Any) -> Any:
        """Check ``value`` against this parameter's type and range; return it converted."""
        if value is None:
            return None
        if self.kind == "float":
            return check_number(self.name, value, self.low, self.high, self.unit,
                                low_open=self.low_open)
        if self.kind == "int":
            lo = None if self.low is None else int(self.low)
            hi = None if self.high is None else int(self.high)
            return check_int(self.name, value, lo, hi)
        if self.kind == "choice":
            return check_choice(self.name, value, self.choices)
        if self.kind == "bool":
            if not isinstance(value, (bool, np.bool_)):
                raise ParameterTypeError(f"{self.name} must be True or False, got {value!r} "
                                f"({type(value).__name__})")
            return bool(value)
        return value

    def range_text(self) -> str:
        if self.kind == "choice":
            return " | ".join(map(str, self.choices))
        if self.kind == "bool":
            return "True | False"
        if self.kind in ("float", "int"):
            lo = "-inf" if self.low is None else f"{self.low:g}"
            hi = "inf" if self.high is None else f"{self.high:g}"
            return f"{'(' if self.low_open else '['}{lo}, {hi}]"
        return ""

    def doc_entry(self, indent: str = "") -> str:
        """This parameter as a numpydoc entry (two lines, the second indented 4 more):
        name, kind, unit, range and default, then its meaning."""
        head = f"{self.name} : {self.kind}"
        if self.unit:
            head += f" [{self.unit}]"
        rng = self.range_text()
        if self.kind in ("float", "int", "choice") and rng:
            head += f", {rng}"
        if self.default is None:
            head += ", optional"
        else:
            head += f", default {self.default:g}" if self.kind in ("float", "int") \
                else f", default {self.default!r}"
        doc = self.doc
        return f"{indent}{head}\n{indent}    {doc}{'' if doc.endswith('.') else '.'}"


def _guard_directions(method):
    """Wrap a model's ``radiance``/``xyz``/``luminance`` so that complex or non-numeric
    directions are refused (TypeError naming ``directions``) whatever path the model takes
    to its kernels; NaN, shape and zero-length checks stay with the model's own validation
    (:func:`skydome._validate.as_directions` or its kernel twin)."""

    @functools.wraps(method)
    def checked(self, directions, *args, **kwargs):
        check_real("directions", directions)
        return method(self, directions, *args, **kwargs)

    checked._guards_directions = True
    return checked


class SkyModel:
    """Base class of every sky model (see the module docstring for the protocol)."""

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        for meth in ("radiance", "xyz", "luminance"):
            f = cls.__dict__.get(meth)
            if callable(f) and not getattr(f, "_guards_directions", False):
                setattr(cls, meth, _guard_directions(f))

    name: ClassVar[str] = ""
    reference: ClassVar[str] = ""
    native: ClassVar[str] = "spectral"
    parameters: ClassVar[tuple[Parameter, ...]] = ()
    summary: ClassVar[str] = ""

    sun = None  # a skydome.Sun where the model has one

    #: Sun elevations [deg] (inclusive) where the model applies.
    sun_elevation_range_deg: ClassVar[tuple[float, float]] = (-90.0, 90.0)
    #: What happens with the sun outside that range: "raise" (ValueError naming
    #: ``sun.elevation_deg``, the model and the range) or "black" (the model is built and
    #: its sky is black, luminance 0 everywhere). A model that supports every elevation by
    #: a documented extension (twilight) declares the full range [-90, 90].
    sun_outside_range: ClassVar[str] = "raise"

    # -- capabilities (module docstring): safe defaults, each model sets its own ---------
    #: The viewer's shader for the model (None: not in the viewer).
    viewer_shader: ClassVar[str | None] = None
    #: The model parameters the viewer's page exposes.
    viewer_parameters: ClassVar[tuple[str, ...]] = ()
    #: The layout of the model's LUT bake, "bruneton" or "hillaire" (None: no bake).
    lut_layout: ClassVar[str | None] = None
    #: Whether skydome.effects.airlight may use the model's ``aerial_perspective``.
    airlight: ClassVar[bool] = False
    #: Keywords skydome.effects.airlight passes to ``aerial_perspective``.
    airlight_options: ClassVar[Mapping[str, Any]] = MappingProxyType({})
    #: What the model returns below the horizon: None (nothing), "sun_and_sky", "sun" or
    #: "own" (its own ground, lit by its sun and sky, by its sun only, or by its own rules).
    own_ground: ClassVar[str | None] = None

    # -- the common constructor --------------------------------------------------------
    def __init__(self, sun=None, **params):
        """Validate ``sun`` and the keyword parameters against the declarations, resolve
        the atmosphere, then call the model's own :meth:`_setup`."""
        p = self._begin(sun, params)
        self._setup(p, params)

    def _setup(self, p: dict[str, Any], given: dict[str, Any]) -> None:
        """The model's own set-up, after the common checks; ``p`` holds every declared
        parameter (validated, defaults filled, ``atmosphere`` resolved), ``given`` the
        caller's keywords. The default stores ``p`` as attributes."""
        for k, v in p.items():
            setattr(self, k, v)

    def _begin(self, sun, params: dict[str, Any]) -> dict[str, Any]:
        """The common constructor work, once for every model: the sun is a
        :class:`skydome.Sun`; every keyword is declared and valid; the sun is inside the
        declared range (or the model is marked black); the atmosphere is resolved where
        the model declares one. Sets ``self.sun`` and ``self._black``."""
        check_sun(sun)
        p = self._validate_params(params)
        self.sun = sun
        self._black = not self.sun_in_range(sun.elevation_deg)
        if self._black and self.sun_outside_range == "raise":
            raise ValueError(self._sun_range_message(sun.elevation_deg))
        if "atmosphere" in p and "turbidity" in p:
            p["atmosphere"] = resolve_atmosphere(p, params)
        return p

    @classmethod
    def sun_in_range(cls, elevation_deg: float) -> bool:
        """Whether the model applies with the sun at ``elevation_deg`` [deg]."""
        lo, hi = cls.sun_elevation_range_deg
        return lo <= float(elevation_deg) <= hi

    @classmethod
    def _sun_range_message(cls, elevation_deg: float) -> str:
        lo, hi = cls.sun_elevation_range_deg
        return (f"sun.elevation_deg = {float(elevation_deg):g} deg is out of range "
                f"[{lo:g}, {hi:g}] deg for model {cls.name!r}")

    # -- helpers for subclasses -------------------------------------------------------
    @classmethod
    def _validate_params(cls, params: dict[str, Any]) -> dict[str, Any]:
        """Validate keyword parameters against ``cls.parameters``; fill defaults.

        Unknown keywords raise TypeError naming the valid ones.
        """
        known = {p.name: p for p in cls.parameters}
        unknown = sorted(set(params) - set(known))
        if unknown:
            raise TypeError(
                f"model {cls.name!r} got unknown parameter(s) {', '.join(unknown)}; "
                f"valid: {', '.join(known) or 'none'}")
        out = {}
        for pname, p in known.items():
            out[pname] = p.validate(params.get(pname, p.default))
        return out

    # -- the three views of the sky -----------------------------------------------------
    def radiance(self, directions, wavelengths_nm) -> np.ndarray:
        """Spectral radiance [W m^-2 sr^-1 nm^-1], shape (..., n_wavelengths)."""
        if self.native == "luminance":
            raise TypeError(f"model {self.name!r} is luminance-only: use luminance() or xyz()")
        if self.native == "xyz":
            # Reconstruct a daylight spectrum with the model's chromaticity (CIE 015 daylight
            # basis S0 + M1 S1 + M2 S2), scaled to the model's luminance.
            from skydome.spectra import spectrum_from_xyz_daylight

            return spectrum_from_xyz_daylight(self.xyz(directions), wavelengths_nm)
        raise NotImplementedError(f"{type(self).__name__} must implement radiance()")

    def xyz(self, directions) -> np.ndarray:
        """CIE 1931 XYZ tristimulus values with Y = luminance [cd m^-2], shape (..., 3)."""
        if self.native == "spectral":
            from skydome.spectra import default_wavelengths, spectrum_to_xyz

            wl = default_wavelengths()
            return spectrum_to_xyz(self.radiance(directions, wl), wl)
        if self.native == "luminance":
            # Luminance-only models carry no colour: give them the chromaticity of CIE
            # illuminant D65 (x, y) = (0.31271, 0.32902) so that images are neutral.
            Y = self.luminance(directions)
            x, y = 0.31271, 0.32902
            return np.stack([Y * x / y, Y, Y * (1.0 - x - y) / y], axis=-1)
        raise NotImplementedError(f"{type(self).__name__} must implement xyz()")

    def luminance(self, directions) -> np.ndarray:
        """Luminance [cd m^-2], shape (...)."""
        if self.native == "luminance":
            raise NotImplementedError(f"{type(self).__name__} must implement luminance()")
        return self.xyz(directions)[..., 1]

    def sun_radiance(self, wavelengths_nm) -> np.ndarray | None:
        """Spectral radiance of the sun's disc as seen by the observer
        [W m^-2 sr^-1 nm^-1], shape (n_wavelengths,); None if the model has no sun."""
        return None

    def sun_luminance(self) -> float | None:
        """Mean luminance of the solar disc seen by the observer [cd m^-2]; None if the
        model has no sun.

        Spectral and XYZ models derive it from :meth:`sun_radiance` (683 lm/W x the
        integral with y-bar over the default grid); luminance-only models that carry a sun
        (Perez 1993, ASRC-CIE, the CIE skies given a direct normal illuminance) override
        it. Renders paint the disc with this value where a model has no spectral sun."""
        from skydome.spectra import default_wavelengths, luminance_from_spectrum

        if self.native == "luminance":
            return None
        wl = default_wavelengths()
        ls = self.sun_radiance(wl)
        if ls is None:
            return None
        return float(luminance_from_spectrum(np.asarray(ls, dtype=np.float64).reshape(-1), wl))

    def direct_normal_illuminance(self) -> float:
        """Illuminance of the sun's disc on a plane facing it [lx]: :meth:`sun_luminance`
        times the disc's solid angle; 0 for a model without a sun. (The whole disc: the
        part below the horizon is not removed; :mod:`skydome.illuminance` counts the sun
        only while its centre is above the horizon.)"""
        lum = self.sun_luminance()
        if lum is None or self.sun is None:
            return 0.0
        return float(lum) * float(self.sun.solid_angle_sr)

    def describe(self) -> dict[str, Any]:
        """The model's name, reference, native quantity and parameter values; a value that
        describes itself (an Atmosphere) by its own ``describe()``."""
        values = {}
        for p in self.parameters:
            v = getattr(self, p.name, None)
            values[p.name] = v.describe() if callable(getattr(v, "describe", None)) else v
        return {"model": self.name, "reference": self.reference, "native": self.native,
                "parameters": values}

    def __repr__(self) -> str:
        vals = ", ".join(f"{p.name}={getattr(self, p.name, None)!r}" for p in self.parameters)
        return f"{type(self).__name__}({vals})"

    @staticmethod
    def _directions(directions) -> np.ndarray:
        return as_directions(directions)

    @staticmethod
    def _aerial_inputs(directions, distance_m, wavelengths_nm):
        """The checked inputs of ``aerial_perspective``: flat unit directions (k, 3), flat
        distances (k,) [m], wavelengths (n,) [nm] and the broadcast shape (...)."""
        from skydome._validate import as_wavelengths

        d = as_directions(directions)
        wl = as_wavelengths(wavelengths_nm)
        dist = np.asarray(distance_m, dtype=np.float64)
        if not np.all(np.isfinite(dist)) or np.any(dist < 0):
            raise ValueError(f"distance_m = {dist.min() if dist.size else dist} m is out of "
                             "range [0, inf) m")
        shape = np.broadcast_shapes(d.shape[:-1], dist.shape)
        flat = np.broadcast_to(d, shape + (3,)).reshape(-1, 3)
        return flat, np.broadcast_to(dist, shape).reshape(-1), wl, shape

    @staticmethod
    def _aerial_outputs(t, L, shape, object_radiance=None):
        """(transmittance, radiance) reshaped to ``shape`` + (n,); with ``object_radiance``
        the radiance reaching the eye, ``L_0 T + L_in``."""
        n = t.shape[-1]
        t = t.reshape(shape + (n,))
        L = L.reshape(shape + (n,))
        if object_radiance is not None:
            L = np.asarray(object_radiance, dtype=np.float64) * t + L
        return t, L


class GroundEyeAerialPerspective:
    """Mixin giving a model whose eye is on the ground the protocol's ``aerial_perspective``
    from its ``_aerial_rays(directions (k, 3), distances (k,) [m], wavelengths (n,) [nm])
    -> (transmittance (k, n), in-scattered radiance (k, n))``, which takes a direction below
    the horizon as the horizontal direction of the same azimuth. Put it before
    :class:`SkyModel` among the bases."""

    def aerial_perspective(self, directions, distance_m, wavelengths_nm, object_radiance=None):
        """Transmittance and in-scattered radiance between the eye (on the ground) and an
        object at ``distance_m`` along ``directions`` (by the model's ``_aerial_rays``).

        Parameters
        ----------
        directions : array_like (..., 3)
            Unit vectors from the eye towards the object (z < 0 is taken as the horizontal
            direction of the same azimuth: the eye is on the flat ground).
        distance_m : float or array_like (...)
            Distance to the object [m], >= 0; broadcast with the directions.
        wavelengths_nm : array_like (n,)
        object_radiance : array_like (..., n), optional
            Radiance leaving the object towards the eye [W m^-2 sr^-1 nm^-1].

        Returns
        -------
        transmittance : (..., n)
        radiance : (..., n)
            The in-scattered radiance L_in [W m^-2 sr^-1 nm^-1]; when ``object_radiance``
            is given, the radiance reaching the eye, ``L_0 T + L_in``.
        """
        dd, dist_f, wl, shape = self._aerial_inputs(directions, distance_m, wavelengths_nm)
        t, L = self._aerial_rays(dd, dist_f, wl)
        return self._aerial_outputs(t, L, shape, object_radiance)


# -- shared by the physically based models ---------------------------------------------------
# One declaration per shared parameter, with the range that is enforced. The observer must
# also be inside the atmosphere (below ``Atmosphere.top_altitude_m``, 100 km for
# ``Atmosphere.earth``), which :func:`resolve_atmosphere` checks against the atmosphere
# actually used.
ATMOSPHERE = Parameter("atmosphere", "", None,
                       doc="skydome.Atmosphere (default Atmosphere.earth(turbidity))",
                       kind="object")
TURBIDITY = Parameter("turbidity", "", 2.5, 1.0, 32.0,
                      "Preetham turbidity when no atmosphere is given")
OBSERVER_ALTITUDE_M = Parameter("observer_altitude_m", "m", 0.0, 0.0, 99_999.0,
                                "observer altitude above the ground (inside the atmosphere)")
#: The declarations every model built on an Atmosphere takes, in this order.
ATMOSPHERE_PARAMETERS = (ATMOSPHERE, TURBIDITY, OBSERVER_ALTITUDE_M)

def check_sun(sun) -> None:
    """TypeError unless ``sun`` is a :class:`skydome.Sun`."""
    from skydome.sun import Sun

    if not isinstance(sun, Sun):
        raise TypeError(f"sun must be a skydome.Sun, not {type(sun).__name__}")


def resolve_atmosphere(p: dict[str, Any], given: dict[str, Any]):
    """The Atmosphere of a model with ``atmosphere``, ``turbidity`` and
    ``observer_altitude_m`` parameters: ``p["atmosphere"]`` or ``Atmosphere.earth(turbidity=
    p["turbidity"])``; refuses both at once (``given`` are the caller's keywords) and an
    observer at or above the top of the atmosphere."""
    from skydome.atmosphere import Atmosphere

    atm = p["atmosphere"]
    if atm is None:
        atm = Atmosphere.earth(turbidity=p["turbidity"])
    elif not isinstance(atm, Atmosphere):
        raise TypeError(f"atmosphere must be a skydome.Atmosphere, not {type(atm).__name__}")
    elif "turbidity" in given:
        raise ValueError("give either atmosphere or turbidity, not both")
    h = p.get("observer_altitude_m")
    if h is not None and h >= atm.top_altitude_m:
        raise ValueError(f"observer_altitude_m = {h:g} m is out of range "
                         f"[0, {atm.top_altitude_m:g}) m (inside the atmosphere)")
    return atm


# -- registry -------------------------------------------------------------------------------
_REGISTRY: dict[str, type[SkyModel]] = {}
_DISCOVERED = False
_PACKAGES = ("skydome.models.analytic", "skydome.models.simulated", "skydome.models.fitted")


#: The values of ``SkyModel.own_ground``.
OWN_GROUND = (None, "sun_and_sky", "sun", "own")


def check_capabilities(cls: type[SkyModel]) -> None:
    """ValueError (naming the model, the attribute and its value) unless the capability
    attributes of ``cls`` are coherent with its declarations (module docstring)."""
    names = {p.name for p in cls.parameters}
    shader = cls.viewer_shader
    if shader is not None and not (isinstance(shader, str) and shader.isidentifier()):
        raise ValueError(f"model {cls.name!r}: viewer_shader = {shader!r} is not None or a "
                         "shader name (an identifier)")
    extra = [k for k in cls.viewer_parameters if k not in names]
    if extra or isinstance(cls.viewer_parameters, str):
        raise ValueError(f"model {cls.name!r}: viewer_parameters = {cls.viewer_parameters!r} "
                         f"names parameters it does not declare ({', '.join(extra)}); valid: "
                         f"{', '.join(sorted(names)) or 'none'}")
    if shader is None and cls.viewer_parameters:
        raise ValueError(f"model {cls.name!r}: viewer_parameters = {cls.viewer_parameters!r} "
                         "without a viewer_shader")
    if cls.lut_layout is not None and not isinstance(cls.lut_layout, str):
        raise ValueError(f"model {cls.name!r}: lut_layout = {cls.lut_layout!r} is not None "
                         "or a layout name")
    if not isinstance(cls.airlight, bool):
        raise ValueError(f"model {cls.name!r}: airlight = {cls.airlight!r} is not True or False")
    if cls.airlight and not (callable(getattr(cls, "aerial_perspective", None))
                             and "turbidity" in names):
        raise ValueError(f"model {cls.name!r}: airlight = True needs an aerial_perspective "
                         "method and a turbidity parameter")
    if cls.airlight_options and not cls.airlight:
        raise ValueError(f"model {cls.name!r}: airlight_options = {dict(cls.airlight_options)!r} "
                         "without airlight = True")
    if cls.own_ground not in OWN_GROUND:
        raise ValueError(f"model {cls.name!r}: own_ground = {cls.own_ground!r} is not one of "
                         f"{', '.join(map(repr, OWN_GROUND))}")


#: The placeholder line of a model's docstring that :func:`register` replaces by the
#: numpydoc entries of :data:`ATMOSPHERE_PARAMETERS` (their one description).
ATMOSPHERE_PARAMETERS_DOC = "{atmosphere_parameters}"


def fill_parameter_docs(cls: type[SkyModel]) -> None:
    """Replace each line ``{atmosphere_parameters}`` of the docstring of ``cls`` by the
    entries of :data:`ATMOSPHERE_PARAMETERS` (:meth:`Parameter.doc_entry`, at that line's
    indent), so that the shared parameters are described once, by their declarations.
    ValueError (naming the model) where the class does not declare them all."""
    doc = cls.__dict__.get("__doc__")
    if not doc or ATMOSPHERE_PARAMETERS_DOC not in doc:
        return
    names = {p.name for p in cls.parameters}
    missing = [p.name for p in ATMOSPHERE_PARAMETERS if p.name not in names]
    if missing:
        raise ValueError(f"model {cls.name!r}: docstring has {ATMOSPHERE_PARAMETERS_DOC} but "
                         f"the model does not declare {', '.join(missing)}")
    lines = []
    for line in doc.split("\n"):
        if line.strip() == ATMOSPHERE_PARAMETERS_DOC:
            indent = line[:len(line) - len(line.lstrip())]
            lines += [p.doc_entry(indent) for p in ATMOSPHERE_PARAMETERS]
        else:
            lines.append(line)
    cls.__doc__ = "\n".join(lines)


def register(cls: type[SkyModel]) -> type[SkyModel]:
    """Class decorator adding a model to the registry under ``cls.name``; its capabilities
    are checked first (:func:`check_capabilities`) and the shared parameters' entries
    written into its docstring (:func:`fill_parameter_docs`)."""
    if not cls.name:
        raise ValueError(f"{cls.__name__} has no name")
    check_capabilities(cls)
    fill_parameter_docs(cls)
    if cls.name in _REGISTRY and _REGISTRY[cls.name] is not cls:
        raise ValueError(f"model name {cls.name!r} registered twice")
    _REGISTRY[cls.name] = cls
    return cls


def unregister(name: str) -> None:
    """Remove the model registered under ``name`` (a model made for a test, say);
    KeyError if there is none."""
    if name not in _REGISTRY:
        raise KeyError(f"model = {name!r} is not registered")
    del _REGISTRY[name]


def _discover() -> None:
    global _DISCOVERED
    if _DISCOVERED:
        return
    for pkg_name in _PACKAGES:
        pkg = importlib.import_module(pkg_name)
        for info in pkgutil.iter_modules(pkg.__path__):
            if not info.name.startswith("_"):
                importlib.import_module(f"{pkg_name}.{info.name}")
    _DISCOVERED = True


def available() -> dict[str, type[SkyModel]]:
    """Every registered model, by name (sorted)."""
    _discover()
    return dict(sorted(_REGISTRY.items()))


def _import_named(name: str) -> None:
    """Import the module of the model packages named ``name`` (a model's module bears its
    name: ``skydome.models.simulated.precomputed``, ``skydome.models.fitted``), where there is
    one, so that a model is found without importing every other model's module: 0.02-0.04 s
    of a warm ``skydome render`` (docs/performance.md). A name without such a module is
    left to the whole discovery."""
    if not name.isidentifier() or name.startswith("_"):
        return
    for pkg_name in _PACKAGES:
        if pkg_name.rsplit(".", 1)[1] == name:
            importlib.import_module(pkg_name)
            return
        if importlib.util.find_spec(f"{pkg_name}.{name}") is not None:
            importlib.import_module(f"{pkg_name}.{name}")
            return


def get_model_class(name: str) -> type[SkyModel]:
    """The model class registered under ``name``; ValueError listing the names otherwise."""
    if isinstance(name, str) and name not in _REGISTRY:
        _import_named(name)
    if name in _REGISTRY:
        return _REGISTRY[name]
    models = available()
    if name not in models:
        raise ValueError(f"model = {name!r} is not one of {', '.join(models)}")
    return models[name]


def model(name: str, **params: Any) -> SkyModel:
    """Construct the model registered under ``name`` with keyword parameters.

    Examples
    --------
    >>> import skydome as sd
    >>> sky = sd.model("single_scattering", sun=sd.Sun(elevation_deg=30, azimuth_deg=135))
    """
    return get_model_class(name)(**params)
