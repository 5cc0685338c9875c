"""The sun as a light for renderers, in the convention of the environment map it goes with.

:func:`sun_light` returns a JSON-ready dictionary: the direction towards the sun in the
convention's axes (and in ENU), the angular radius, the spectral normal irradiance of the
visible part of the disc at the ground [W m^-2 nm^-1], its RGB (the maps' scale: Rec. 709
primaries, W m^-2 with 683 lm/W), the normal illuminance [lx], and what each target takes:

* Blender sun lamp: ``strength`` [W m^-2] and ``color`` (the RGB irradiance divided by its
  largest channel) with strength x color = the RGB irradiance, so that the lamp's
  illuminance is 683 lm/W x Y(strength x color) = ``illuminance_lx``; ``angle`` = the
  disc's angular diameter; the lamp shines along -direction.
* Mitsuba 3 ``directional`` emitter, in Mitsuba's units (the module docstring of
  :mod:`skydome.export.conventions`, unless ``units`` says otherwise for the mitsuba
  convention): ``irradiance_rgb`` (RGB irradiance / 106.7503 of the photometric one), and
  ``irradiance_spectrum``, the spectral irradiance [W m^-2 nm^-1] itself as a Mitsuba
  ``spectrum`` (wavelength, value) list, which Mitsuba's spectral and RGB variants both
  take as it is; ``direction`` = the direction the light travels (minus the direction to
  the sun) in Mitsuba's axes (+X east, +Y up, +Z south; Y-up like its ``envmap``).
* glTF ``KHR_lights_punctual`` directional light: ``intensity`` [lx] and ``color`` with
  intensity x color = the illuminance per RGB channel (as three.js and most viewers
  multiply them); the light points along its node's local -Z, turned to -direction.

The irradiance is ``sky.sun_radiance(wl) x sun.solid_angle_sr x visible fraction`` (the
part of the disc above the horizon, flat circular-segment geometry as skydome.imaging; a
model whose ``sun_radiance`` already counts its horizon, ``sun_visible_fraction()``, has it
divided out first: :func:`skydome.imaging.sun_disc.sun_disc_radiance`).

Physical forms (``spectral_irradiance_W_m2_nm``, ``rgb_irradiance_W_m2`` on the photometric
scale, ``illuminance_lx``) are always given; ``rgb_irradiance_map_units`` is the RGB in the
units of the map written with the light (``units``, default the convention's own).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from skydome.export.conventions import get_convention, get_units, resolve_units

__all__ = ["sun_light", "sun_light_from", "write_sun_json"]

_K_M = 683.0


def sun_light(sky, convention: str = "skydome", wavelengths_nm=None,
              units: str | None = None) -> dict | None:
    """The sun of ``sky`` as a light (see the module docstring) at ``wavelengths_nm``
    (default :func:`skydome.spectra.default_wavelengths`); None if the model has no sun
    with a radiance, or the sun is wholly below the horizon.

    ``units``: the scale of the map the light goes with (a name of
    :data:`skydome.export.conventions.UNITS`), default the convention's own; it sets
    ``rgb_irradiance_map_units`` and, for the mitsuba convention, the Mitsuba target.
    """
    from skydome.imaging.sun_disc import sun_light as render_sun_light
    from skydome.spectra import default_wavelengths

    resolve_units(get_convention(convention), units)      # ValueError naming units, first
    wl = default_wavelengths() if wavelengths_nm is None else np.asarray(wavelengths_nm, float)
    # the render layer's sun light: the limb-darkened disc's spectral normal irradiance,
    # times the part of its flux above the horizon (per wavelength)
    base = render_sun_light(sky, wl)
    if base is None or getattr(sky, "native", "spectral") == "luminance":
        return None
    return sun_light_from(base, sky.sun, convention, units)


def sun_light_from(base, sun, convention: str = "skydome", units: str | None = None) -> dict:
    """The light of :func:`sun_light` made from a render's sun light ``base`` (a
    :class:`skydome.imaging.sun_disc.SunLight`: ``SkyImage.sun_light``) and the
    :class:`skydome.Sun` it comes from. A spectral ``base`` gives every field; an XYZ one
    (a luminance-only model's sun, D65 chromaticity) leaves the wavelengths and the
    spectral irradiance None. ``units`` as in :func:`sun_light`."""
    from skydome.spectra import spectrum_to_xyz, xyz_to_linear_srgb

    conv = get_convention(convention)
    map_units = resolve_units(conv, units)               # ValueError naming units
    # Mitsuba's target is in Mitsuba's units, unless a mitsuba map is written in others
    mi_units = map_units if conv.name == "mitsuba" else get_units("mitsuba")
    E = np.asarray(base.irradiance, dtype=np.float64)     # W m^-2 nm^-1, or XYZ [lx]
    frac = base.visible_fraction
    spectral = base.wavelengths_nm is not None
    wl = np.asarray(base.wavelengths_nm, dtype=np.float64) if spectral else None
    xyz = spectrum_to_xyz(E, wl) if spectral else E                     # Y = illuminance [lx]
    rgb = np.maximum(xyz_to_linear_srgb(xyz), 0.0) / _K_M               # W m^-2, map scale
    lux = float(xyz[1])
    d_enu = np.asarray(sun.direction, dtype=np.float64)
    d_tool = conv.to_tool(d_enu)
    peak = float(rgb.max()) if rgb.max() > 0 else 1.0
    colour = [float(c) / peak for c in rgb]            # strength x colour = RGB irradiance
    strength = peak
    mi = get_convention("mitsuba")
    mitsuba = {"type": "directional",
               "direction": [-float(x) for x in mi.to_tool(d_enu)],
               "units": mi_units.name,
               "irradiance_rgb": [float(c) * mi_units.scale for c in rgb],
               "note": "Mitsuba axes: +X east, +Y up, +Z south (convention mitsuba); "
                       f"irradiance in {mi_units.name} units"}
    if mi_units.name == "mitsuba" and spectral:
        # Mitsuba's units are spectral radiometry: the physical spectral irradiance is its
        # own value (Y = integral E y-bar dl / 106.7503 in its films); the dictionary is
        # Mitsuba's as it stands (a 'spectrum' takes exactly 'type' and 'value')
        mitsuba["irradiance_spectrum"] = {
            "type": "spectrum", "value": [[float(w), float(e)] for w, e in zip(wl, E)]}
        mitsuba["note"] += ("; irradiance_spectrum: [nm, W m^-2 nm^-1] pairs, the physical "
                            "spectral irradiance, for 'irradiance' as it stands")
    return {
        "convention": conv.name,
        "direction_to_sun": [float(x) for x in d_tool],
        "direction_to_sun_enu": [float(x) for x in d_enu],
        "elevation_deg": float(sun.elevation_deg), "azimuth_deg": float(sun.azimuth_deg),
        "angular_radius_deg": float(sun.angular_radius_deg),
        "visible_fraction": float(frac),
        "wavelengths_nm": [float(w) for w in wl] if spectral else None,
        "spectral_irradiance_W_m2_nm": [float(e) for e in E] if spectral else None,
        "rgb_irradiance_W_m2": [float(c) for c in rgb],
        "rgb_colour_space": "linear Rec. 709 / sRGB primaries, D65; 683 lm/W",
        "map_units": map_units.name,
        "rgb_irradiance_map_units": [float(c) * map_units.scale for c in rgb],
        "illuminance_lx": lux,
        "targets": {
            "blender": {"type": "SUN", "strength_W_m2": strength, "color": colour,
                        "angle_deg": 2.0 * float(sun.angular_radius_deg),
                        "points_along": [-float(x) for x in d_enu],
                        "note": "Blender axes: +X east, +Y north, +Z up (convention blender)"},
            "mitsuba": mitsuba,
            "gltf_KHR_lights_punctual": {"type": "directional", "intensity_lx": _K_M * peak,
                                         "color": colour,
                                         "points_along": [-float(x) for x in d_tool],
                                         "note": "the light shines along its node's -Z"},
        },
        "units": {"spectral_irradiance": "W m^-2 nm^-1", "rgb_irradiance": "W m^-2",
                  "illuminance": "lx", "angles": "deg",
                  "rgb_irradiance_map_units": map_units.description},
    }


def sun_json_writer(light: dict):
    """``write(tmp)``: writes ``light`` as JSON to the file ``tmp`` (for a map's ``also``
    files, :meth:`skydome.export.envmap.EnvMap.write`)."""
    def write(tmp) -> None:
        with open(tmp, "w", encoding="utf-8") as f:
            json.dump(light, f, indent=2)
    return write


def write_sun_json(light: dict, path) -> Path:
    """Write ``light`` as JSON atomically (.json only); returns the path."""
    from skydome._io import atomic_file, check_output_file

    p = check_output_file(path, (".json",), name="sun light file")
    with atomic_file(p) as tmp:
        sun_json_writer(light)(tmp)
    return p
