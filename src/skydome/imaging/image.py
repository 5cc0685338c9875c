"""SkyImage: rendered sky pixels (spectral or XYZ), colour, tone mapping and file writers.

Colour pipeline: spectral radiance [W m^-2 sr^-1 nm^-1] -> CIE 1931 XYZ with Y the
luminance [cd m^-2] (683 lm/W) -> linear sRGB (Rec. 709 primaries, D65 white) on the same
scale (so that an (R, G, B) of (1, 1, 1) has a luminance of 1 cd m^-2) -> for display:
exposure, the Hunt-effect chroma gain, display transform, sRGB encoding
(:mod:`skydome.imaging.display`).

Writers (chosen by the file suffix; every write is atomic: a temporary file beside the
target, renamed over it on success and removed on failure):

``.exr``
    OpenEXR, float32 channels R, G, B (linear sRGB, cd m^-2 scale) and Y (luminance,
    cd m^-2), ZIP compressed, with the standard ``chromaticities`` (Rec. 709/D65) and
    ``whiteLuminance`` = 1 cd m^-2 attributes and string attributes naming the units, the
    model and its parameters and the projection.
``.hdr``
    Radiance RGBE picture [Ward91] written by our own encoder: linear sRGB radiance in
    Radiance's convention, value = RGB [cd m^-2] / 179, 179 lm/W being Radiance's
    luminous efficacy of equal-energy white light (``WHTEFFICACY`` in ``color.h``), so
    that Radiance tools (``pvalue -o``, ``pcomb``, ``evalglare``) report luminance as
    ``179 * (0.2651 R + 0.6701 G + 0.0648 B)`` for their own primaries. Flat (non-RLE)
    scanlines; a ``PRIMARIES=`` line names the Rec. 709 primaries and D65 white.
``.png``
    Display-referred sRGB after exposure and tone mapping, 8 or 16 bit (our
    own PNG encoder, zlib + struct).

References
----------
.. [Ward91] G. Ward, "Real pixels", in Graphics Gems II, J. Arvo (ed.), Academic Press,
   1991, pp. 80-83 (RGBE encoding, Radiance picture format).
.. [Rei02] E. Reinhard, M. Stark, P. Shirley, J. Ferwerda, "Photographic tone
   reproduction for digital images", ACM TOG 21(3), 2002 (eq. 1 log-average luminance,
   key 0.18, eq. 3 L / (1 + L)).
.. [Nar15] K. Narkowicz, "ACES filmic tone mapping curve", blog post, 2015
   (f(x) = x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)).
.. [PNG] W3C, Portable Network Graphics (PNG) Specification, 2nd ed., 2003.
"""

from __future__ import annotations

import json
import os
import struct
import zlib
from pathlib import Path
from typing import Any

import numpy as np

from skydome._io import atomic_write as _atomic_write
from skydome._validate import check_choice

__all__ = ["SkyImage", "check_output_path", "read_hdr", "read_exr", "read_png16",
           "tonemap_curve", "SUFFIXES", "WHITE_EFFICACY"]

SUFFIXES = (".exr", ".hdr", ".png")
TONEMAPS = ("clamp", "reinhard", "filmic", "hue-preserving", "agx", "aces-hill")
#: Default display transform (skydome.imaging.display): hue-preserving, gamut compressed.
DEFAULT_TONEMAP = "hue-preserving"
#: Radiance's luminous efficacy of equal-energy white [lm/W] (WHTEFFICACY, color.h).
from skydome.constants import RADIANCE_WHITE_EFFICACY as WHITE_EFFICACY  # noqa: E402
#: Pixels brighter than this [cd m^-2] (the sun's disc) are left out of auto exposure.
AUTO_EXPOSURE_CUTOFF = 1.0e5
#: Reinhard's key value: the log-average luminance maps to this display value [Rei02].
KEY = 0.18
_DELTA = 1.0e-6  # [Rei02] eq. 1 small delta [cd m^-2] against log(0)

UNITS = "cd/m^2, linear Rec.709/sRGB primaries (D65)"
#: .hdr files follow Radiance's convention, not cd/m^2 (see the module docstring)
HDR_UNITS = ("Radiance convention: radiance per channel in W sr^-1 m^-2 with 179 lm/W "
             "(WHTEFFICACY), i.e. value = linear Rec.709/sRGB RGB in cd/m^2 / 179; luminance "
             "= 179 x (0.2126 R + 0.7152 G + 0.0722 B); scene-referred, no exposure applied")
_SRGB_CHROMATICITIES = (0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290)


# --------------------------------------------------------------------------------------
# Paths and atomic writes
# --------------------------------------------------------------------------------------

def check_output_path(path) -> Path:
    """Validate an output file name before any work.

    Raises ValueError (naming the file) if the suffix is not .exr, .hdr or .png, if the
    folder does not exist or is not writable, or if the path is an existing folder.
    """
    p = Path(path)
    if p.suffix.lower() not in SUFFIXES:
        raise ValueError(f"output file {str(p)!r} has suffix {p.suffix!r}: it must be one of "
                         f"{', '.join(SUFFIXES)}")
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise ValueError(f"output file {str(p)!r}: folder {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"output file {str(p)!r}: folder {str(parent)!r} is not writable")
    if p.is_dir():
        raise ValueError(f"output file {str(p)!r} is an existing folder")
    return p


# --------------------------------------------------------------------------------------
# Tone mapping
# --------------------------------------------------------------------------------------

def tonemap_curve(x, tonemap: str = "filmic") -> np.ndarray:
    """Display value in [0, 1] of exposed linear values ``x`` (negatives clipped to 0).

    ``clamp``: min(x, 1). ``reinhard``: x / (1 + x) [Rei02] eq. 3, applied per channel.
    ``filmic``: the ACES fit of [Nar15], x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14),
    clipped to 1 (it tends to 1.033).
    """
    check_choice("tonemap", tonemap, TONEMAPS[:3])
    x = np.maximum(np.asarray(x, dtype=np.float64), 0.0)
    if tonemap == "clamp":
        y = x
    elif tonemap == "reinhard":
        y = x / (1.0 + x)
    else:
        y = x * (2.51 * x + 0.03) / (x * (2.43 * x + 0.59) + 0.14)
    return np.clip(y, 0.0, 1.0)


# --------------------------------------------------------------------------------------
# The image
# --------------------------------------------------------------------------------------

class SkyImage:
    """A rendered sky image.

    Parameters
    ----------
    data : array_like
        Shape (H, W, C): spectral radiance [W m^-2 sr^-1 nm^-1] with C wavelengths
        (``kind="spectral"``) or CIE XYZ with Y in cd m^-2 (``kind="xyz"``, C = 3).
        Masked pixels should be 0.
    kind : {"spectral", "xyz"}
    wavelengths_nm : array_like or None
        Shape (C,) [nm] for spectral data; None for XYZ.
    mask : array_like of bool, optional
        Shape (H, W): True where the pixel shows the sky; default all True.
    projection : Projection, optional
        The projection the pixels were sampled with.
    metadata : dict, optional
        Model name, parameters, sun, ... (written into file headers).
    """

    def __init__(self, data, kind: str, wavelengths_nm=None, mask=None, projection=None,
                 metadata: dict | None = None):
        check_choice("kind", kind, ("spectral", "xyz"))
        data = np.asarray(data, dtype=np.float64)
        if data.ndim != 3:
            raise ValueError(f"data must have shape (H, W, C), got {data.shape}")
        if kind == "spectral":
            if wavelengths_nm is None:
                raise ValueError("wavelengths_nm is required for spectral data")
            from skydome._validate import as_wavelengths

            wl = as_wavelengths(wavelengths_nm)
            if wl.size != data.shape[-1]:
                raise ValueError(f"wavelengths_nm has {wl.size} entries but data has "
                                 f"{data.shape[-1]} channels")
        else:
            if data.shape[-1] != 3:
                raise ValueError(f"xyz data must have 3 channels, got {data.shape[-1]}")
            wl = None
        if mask is None:
            mask = np.ones(data.shape[:2], dtype=bool)
        mask = np.asarray(mask, dtype=bool)
        if mask.shape != data.shape[:2]:
            raise ValueError(f"mask must have shape {data.shape[:2]}, got {mask.shape}")
        self.data = data
        self.kind = kind
        self.wavelengths_nm = wl
        self.mask = mask
        self.projection = projection
        self.metadata = dict(metadata or {})
        #: the sun as a separate light when it was left out of the image (render(draw_sun=False))
        self.sun_light = None

    @property
    def shape(self) -> tuple[int, int]:
        """(H, W) [pixels]."""
        return self.data.shape[:2]

    def __repr__(self) -> str:
        return (f"SkyImage({self.shape[1]}x{self.shape[0]}, kind={self.kind!r}, "
                f"channels={self.data.shape[-1]})")

    # -- colour -------------------------------------------------------------------------
    def xyz(self) -> np.ndarray:
        """CIE 1931 XYZ, Y = luminance [cd m^-2], shape (H, W, 3); 0 where masked."""
        if self.kind == "spectral":
            from skydome.spectra import spectrum_to_xyz

            out = spectrum_to_xyz(self.data, self.wavelengths_nm)
        else:
            out = self.data.copy()
        out[~self.mask] = 0.0
        return out

    def luminance(self) -> np.ndarray:
        """Luminance [cd m^-2], shape (H, W); 0 where masked."""
        return self.xyz()[..., 1]

    def linear_srgb(self) -> np.ndarray:
        """Linear sRGB (Rec. 709, D65) scaled so that Y = 0.2126 R + 0.7152 G + 0.0722 B is
        the luminance [cd m^-2]; shape (H, W, 3); out-of-gamut values may be negative."""
        from skydome.spectra import xyz_to_linear_srgb

        return xyz_to_linear_srgb(self.xyz())

    def adapting_luminance(self) -> float | None:
        """Log-average luminance L̄ [cd m^-2] of the sky pixels, [Rei02] eq. 1: pixels
        brighter than 1e5 cd m^-2 (the sun), black pixels and, where the projection is
        known, pixels below the horizon (the ground) are left out. None if no pixel
        qualifies. It keys :meth:`auto_exposure` and stands for the adapting luminance of
        the scene in the colourfulness gain (:func:`skydome.imaging.display.hunt_chroma_gain`)."""
        held = getattr(self, "_held_adapting", None)
        if held:                   # computed once for the picture being made (_held)
            return held[0]
        if held is not None:
            held.append(self._adapting_luminance())
            return held[0]
        return self._adapting_luminance()

    def _adapting_luminance(self) -> float | None:
        sel = self.mask
        if self.projection is not None:
            # the pixels above the horizon: given by render() for its projection (the
            # directions it sampled), else from the projection's directions
            known = getattr(self, "_above_horizon", None)
            if known is not None and known[0] is self.projection:
                up = known[1]
            else:
                up = self.projection.directions()[0][..., 2] > 0.0
            if np.any(sel & up):
                sel = sel & up
        Y = (self.data[..., 1] if self.kind == "xyz" else self.luminance())[sel]
        Y = Y[(Y > 0.0) & (Y <= AUTO_EXPOSURE_CUTOFF)]
        if Y.size == 0:
            return None
        return float(np.exp(np.mean(np.log(_DELTA + Y))))  # [Rei02] eq. 1

    def _held(self):
        """Context in which :meth:`adapting_luminance` is computed once (the exposure and the
        chroma gain of one picture both need it; each costs the pixel directions and a
        logarithm per sky pixel)."""
        import contextlib

        @contextlib.contextmanager
        def held():
            self._held_adapting = []
            try:
                yield
            finally:
                del self._held_adapting
        return held()

    def auto_exposure(self) -> float:
        """Exposure multiplier k [m^2/cd] mapping the log-average luminance of the sky
        pixels (:meth:`adapting_luminance`) to Reinhard's key 0.18 [Rei02]; 1 if no pixel
        qualifies."""
        log_avg = self.adapting_luminance()
        return 1.0 if log_avg is None else KEY / log_avg

    def chroma_gain(self, hunt: bool = True) -> float:
        """CIELAB chroma gain of the picture: the Hunt-effect compensation
        :func:`skydome.imaging.display.hunt_chroma_gain` of the scene's adapting luminance
        if ``hunt``, else 1."""
        la = self.adapting_luminance() if hunt else None
        if la is None:
            return 1.0
        from skydome.imaging.display import hunt_chroma_gain

        return hunt_chroma_gain(la)

    def exposure_multiplier(self, exposure: float | None = None, ev100: float | None = None) -> float:
        """The exposure multiplier k [m^2/cd]: ``exposure`` if given (> 0), else from
        ``ev100`` (k = 1 / (1.2 x 2^EV100), :mod:`skydome.imaging.display`), else
        :meth:`auto_exposure`."""
        if exposure is not None and ev100 is not None:
            raise ValueError("give exposure or ev100, not both")
        if exposure is not None:
            from skydome._validate import check_number

            return check_number("exposure", exposure, 0.0, None, low_open=True)
        if ev100 is not None:
            from skydome.imaging.display import ev100_to_exposure

            return ev100_to_exposure(ev100)
        return self.auto_exposure()

    def to_srgb(self, exposure: float | None = None, tonemap: str = DEFAULT_TONEMAP,
                ev100: float | None = None, hunt: bool = True) -> np.ndarray:
        """Display values: float (H, W, 3) in [0, 1], sRGB encoded.

        Parameters
        ----------
        exposure : float, optional
            Multiplier k [m^2/cd] on the linear sRGB values in cd m^-2 (> 0); None:
            from ``ev100`` or :meth:`auto_exposure`.
        tonemap : {"hue-preserving", "agx", "aces-hill", "filmic", "reinhard", "clamp"}
            Display transform (:func:`skydome.imaging.display.display_transform`):
            the default keeps hue and compresses the gamut; ``agx`` and ``aces-hill``
            work in their own primaries; the last three act per channel
            (:func:`tonemap_curve`, after clipping out-of-gamut negatives to 0). Masked
            pixels are black.
        ev100 : float, optional
            Exposure value at ISO 100 (alternative to ``exposure``).
        hunt : bool
            Scale the CIELAB chroma by :meth:`chroma_gain` (default), which keeps the
            colourfulness of the bright sky on the dimmer display (the Hunt effect,
            :mod:`skydome.imaging.display`); False shows the chromaticities as they are.
        """
        check_choice("tonemap", tonemap, TONEMAPS)
        with self._held():
            return self._display(self.exposure_multiplier(exposure, ev100), tonemap,
                                 self.chroma_gain(hunt))

    def _display(self, k: float, tonemap: str, gain: float) -> np.ndarray:
        from skydome.imaging.display import display_transform, scale_chroma
        from skydome.spectra import srgb_encode

        rgb = scale_chroma(self.linear_srgb() * k, gain)
        if tonemap == "hue-preserving":
            # the default in one pass per pixel (a numba kernel, as the chroma gain's): the
            # NumPy expression below made about ten full-size temporaries, 0.03-0.05 s of
            # a warm 512 px `skydome render` (docs/performance.md)
            from skydome._threads import run_ranges
            from skydome.imaging._kernels_display import (MIN_PIXELS_PER_THREAD,
                                                          hue_preserving_srgb_kernel)
            from skydome.imaging.display import _LUMA, _WHITE_FULL, _WHITE_START

            flat = np.ascontiguousarray(rgb.reshape(-1, 3), dtype=np.float64)
            out = np.empty_like(flat)
            mask = np.ascontiguousarray(np.broadcast_to(self.mask, rgb.shape[:-1]).reshape(-1))
            nan_counts = run_ranges(hue_preserving_srgb_kernel, flat.shape[0],
                               (flat, _LUMA, _WHITE_START,
                                float(np.log2(_WHITE_FULL / _WHITE_START)), mask, out),
                               MIN_PIXELS_PER_THREAD)
            if sum(nan_counts):
                raise ValueError("linear contains NaN values")
            return out.reshape(rgb.shape)
        if tonemap in TONEMAPS[:3]:   # per-channel curves: out-of-gamut negatives to 0
            rgb = np.maximum(rgb, 0.0)
        out = np.clip(srgb_encode(display_transform(rgb, tonemap)), 0.0, 1.0)
        out[~self.mask] = 0.0
        return out

    # -- writing ------------------------------------------------------------------------
    def save(self, path, exposure: float | None = None, tonemap: str = DEFAULT_TONEMAP,
             bits: int = 8, ev100: float | None = None, hunt: bool = True) -> Path:
        """Write the image; the format follows the suffix (.exr, .hdr, .png).

        ``exposure`` (or ``ev100``), ``tonemap``, ``hunt`` and ``bits`` (8 or 16) apply to PNG
        only; the PNG records them, says it is display-referred and carries an sRGB
        chunk. The write is atomic. Returns the path written.
        """
        p = check_output_path(path)
        check_choice("tonemap", tonemap, TONEMAPS)
        check_choice("bits", bits, (8, 16))
        suffix = p.suffix.lower()
        if suffix == ".exr":
            _atomic_write(p, self._write_exr)
        elif suffix == ".hdr":
            _atomic_write(p, self._write_hdr)
        else:
            with self._held():
                k = self.exposure_multiplier(exposure, ev100)
                gain = self.chroma_gain(hunt)
            display = self._display(k, tonemap, gain)
            from skydome.imaging.display import exposure_to_ev100

            info = {"colour": "display-referred sRGB (IEC 61966-2-1), not radiometric",
                    "exposure_m2_per_cd": float(k), "ev100": round(exposure_to_ev100(k), 4),
                    "exposure_mode": ("explicit" if exposure is not None else
                                      "ev100" if ev100 is not None else "auto (key 0.18)"),
                    "display_transform": tonemap,
                    "chroma_gain": round(gain, 4)}
            _atomic_write(p, lambda tmp: self._write_png(tmp, display, bits, info))
        return p

    def _header_text(self) -> dict[str, str]:
        """String metadata: units, model, parameters, projection, wavelengths."""
        meta = {"units": UNITS, "software": _software()}
        for key, value in self.metadata.items():
            meta[key] = value if isinstance(value, str) else json.dumps(value, default=_json_default)
        if self.projection is not None and "projection" not in meta:
            meta["projection"] = json.dumps(self.projection.describe())
        if self.kind == "spectral" and "wavelengths_nm" not in meta:
            meta["wavelengths_nm"] = json.dumps([float(w) for w in self.wavelengths_nm])
        return meta

    def _write_exr(self, tmp: str) -> None:
        import OpenEXR

        rgb = self.linear_srgb().astype(np.float32)
        Y = self.luminance().astype(np.float32)
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage,
                  "chromaticities": _SRGB_CHROMATICITIES,
                  # RGB (1, 1, 1) has a luminance of 1 cd m^-2
                  "whiteLuminance": 1.0}
        for key, value in self._header_text().items():
            header[f"skydome:{key}" if key not in ("units",) else key] = value
        channels = {"R": np.ascontiguousarray(rgb[..., 0]), "G": np.ascontiguousarray(rgb[..., 1]),
                    "B": np.ascontiguousarray(rgb[..., 2]), "Y": np.ascontiguousarray(Y)}
        from skydome._io import write_exr

        write_exr(tmp, header, channels)  # a full disk: OSError ENOSPC (OpenEXR: RuntimeError)

    def _write_hdr(self, tmp: str) -> None:
        H, W = self.shape
        rgb = np.maximum(self.linear_srgb(), 0.0) / WHITE_EFFICACY
        lines = [b"#?RADIANCE",
                 b"SOFTWARE= " + _software().encode(),
                 b"PRIMARIES= 0.6400 0.3300 0.3000 0.6000 0.1500 0.0600 0.3127 0.3290"]
        for key, value in self._header_text().items():
            if key == "software":
                continue
            if key == "units":
                value = HDR_UNITS
            if key == "wavelengths_nm":
                w = self.wavelengths_nm
                value = f"{w.size} samples {w[0]:g} .. {w[-1]:g} nm"
            text = " ".join(str(value).split())  # one line, ASCII
            if len(text) > 1000:  # keep header lines well inside Radiance's line buffers
                text = text[:996] + " ..."
            lines.append(f"SKYDOME_{key.upper()}= {text}".encode("ascii", "replace"))
        view = getattr(self.projection, "radiance_view", None)
        if view:
            lines.append(f"VIEW= {view}".encode())
        lines.append(b"FORMAT=32-bit_rle_rgbe")
        head = b"\n".join(lines) + b"\n\n" + f"-Y {H} +X {W}\n".encode()
        body = rgbe_encode(rgb).tobytes()
        with open(tmp, "wb") as f:
            f.write(head)
            f.write(body)

    def _write_png(self, tmp: str, display: np.ndarray, bits: int, info: dict | None = None) -> None:
        head = self._header_text()
        head["units"] = "display-referred sRGB code values (scene luminance in cd/m^2 x exposure)"
        head.update({k: v if isinstance(v, str) else json.dumps(v) for k, v in (info or {}).items()})
        text = {"Software": _software(), "Description": json.dumps(head, default=_json_default)}
        text.update({k: str(v) for k, v in (info or {}).items()})
        if bits == 8:
            write_png8(tmp, np.round(display * 255.0).astype(np.uint8), text)
        else:
            write_png16(tmp, np.round(display * 65535.0).astype(np.uint16), text)


# zlib level of 8-bit PNGs: the shortest render's 512 x 512 picture took 120 ms to encode at
# Pillow's default (6) and 26 ms at 1, for 90 kB against 131 kB (the same pixels; a shared
# 2-core EPYC, best of 5; docs/performance.md). Written by :func:`write_png8` since (no
# Pillow import, 0.01-0.02 s of a warm `skydome render`): with every row's "Up" filter the
# same picture is 130.5 kB at level 1 (178 kB unfiltered; Pillow's adaptive filters 135 kB),
# its zlib pass 6 ms.
PNG_COMPRESS_LEVEL = 1


def _software() -> str:
    try:
        from skydome import __version__
    except Exception:  # pragma: no cover
        __version__ = "?"
    return f"skydome {__version__}"


def _json_default(obj):
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, (np.floating, np.integer)):
        return obj.item()
    return str(obj)


# --------------------------------------------------------------------------------------
# RGBE (Radiance) encoding and reading
# --------------------------------------------------------------------------------------

def rgbe_encode(rgb) -> np.ndarray:
    """Encode non-negative RGB floats (..., 3) as RGBE bytes (..., 4) [Ward91]:
    the largest component v = m 2^e with m in [0.5, 1) sets the shared exponent e + 128,
    and each mantissa byte is floor(c * 256 m / v). Values below 1e-32 become (0,0,0,0)."""
    rgb = np.maximum(np.asarray(rgb, dtype=np.float64), 0.0)
    v = rgb.max(axis=-1)
    m, e = np.frexp(v)
    ok = v > 1e-32
    scale = np.where(ok, m * 256.0 / np.where(ok, v, 1.0), 0.0)
    mant = np.clip(np.floor(rgb * scale[..., None]), 0, 255)
    out = np.empty(rgb.shape[:-1] + (4,), dtype=np.uint8)
    out[..., :3] = np.where(ok[..., None], mant, 0).astype(np.uint8)
    out[..., 3] = np.where(ok, np.clip(e + 128, 0, 255), 0).astype(np.uint8)
    return out


def rgbe_decode(rgbe) -> np.ndarray:
    """RGBE bytes (..., 4) -> float32 RGB (..., 3): (c + 0.5) 2^(e - 136), 0 for e = 0
    (Radiance ``colr_color``)."""
    a = np.asarray(rgbe, dtype=np.uint8)
    e = a[..., 3].astype(np.int32)
    f = np.where(e > 0, np.ldexp(1.0, e - (128 + 8)), 0.0)
    return ((a[..., :3].astype(np.float64) + 0.5) * f[..., None]).astype(np.float32)


def read_hdr(path) -> np.ndarray:
    """Read a Radiance RGBE picture ("-Y H +X W" orientation; flat or RLE scanlines).

    Returns
    -------
    numpy.ndarray
        (H, W, 3) float32 in the file's units (Radiance: W sr^-1 m^-2 per channel, i.e.
        for skydome files RGB [cd m^-2] / 179). Any EXPOSURE= header is not applied.
    """
    raw = Path(path).read_bytes()
    if not (raw.startswith(b"#?RADIANCE") or raw.startswith(b"#?RGBE")):
        raise ValueError(f"{str(path)!r} is not a Radiance picture (no #?RADIANCE line)")
    end = raw.find(b"\n\n")
    if end < 0:
        raise ValueError(f"{str(path)!r}: header not terminated")
    header = raw[:end].decode("ascii", "replace").splitlines()
    fmt = [h for h in header if h.startswith("FORMAT=")]
    if fmt and fmt[0].strip() != "FORMAT=32-bit_rle_rgbe":
        raise ValueError(f"{str(path)!r}: unsupported {fmt[0].strip()}")
    nl = raw.index(b"\n", end + 2)
    res = raw[end + 2:nl].decode("ascii").split()
    if len(res) != 4 or res[0] != "-Y" or res[2] != "+X":
        raise ValueError(f"{str(path)!r}: unsupported resolution line {' '.join(res)!r}")
    H, W = int(res[1]), int(res[3])
    buf = np.frombuffer(raw, dtype=np.uint8, offset=nl + 1)
    out = np.empty((H, W, 4), dtype=np.uint8)
    pos = 0
    for y in range(H):
        if (8 <= W <= 0x7FFF and pos + 4 <= buf.size and buf[pos] == 2 and buf[pos + 1] == 2
                and not buf[pos + 2] & 0x80):
            if (int(buf[pos + 2]) << 8 | int(buf[pos + 3])) != W:
                raise ValueError(f"{str(path)!r}: scanline length mismatch in row {y}")
            pos += 4
            for c in range(4):  # new-style RLE: each component run-length coded
                x = 0
                while x < W:
                    n = int(buf[pos])
                    pos += 1
                    if n > 128:
                        n -= 128
                        out[y, x:x + n, c] = buf[pos]
                        pos += 1
                    else:
                        out[y, x:x + n, c] = buf[pos:pos + n]
                        pos += n
                    x += n
        else:  # flat scanline (old-style run pixels (1,1,1,n) are not supported)
            out[y] = buf[pos:pos + 4 * W].reshape(W, 4)
            pos += 4 * W
    return rgbe_decode(out)


# --------------------------------------------------------------------------------------
# EXR reading, 16-bit PNG
# --------------------------------------------------------------------------------------

def read_exr(path) -> dict[str, np.ndarray]:
    """Channels of an OpenEXR file by name, each an (H, W) array (float32 for skydome
    files); the header is under the key ``"header"``."""
    import OpenEXR

    with OpenEXR.File(str(path), separate_channels=True) as f:
        out: dict[str, Any] = {name: np.array(ch.pixels) for name, ch in f.channels().items()}
        out["header"] = dict(f.header())
    return out


def _chunk(kind: bytes, data: bytes) -> bytes:
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)


def write_png8(path, rgb8: np.ndarray, text: dict[str, str] | None = None,
               level: int = PNG_COMPRESS_LEVEL) -> None:
    """Write (H, W, 3) uint8 values as an 8-bit RGB PNG [PNG]: IHDR (bit depth 8, colour
    type 2), an sRGB chunk (rendering intent 0, perceptual: [PNG] 11.3.3.5), tEXt chunks,
    one zlib IDAT at ``level`` whose rows all use filter type 2, "Up" ([PNG] 9.2:
    Filt(x) = Orig(x) - Orig(b) mod 256, b the byte above; the first row's b is 0), IEND."""
    a = np.asarray(rgb8)
    if a.ndim != 3 or a.shape[-1] != 3 or a.dtype != np.uint8:
        raise ValueError(f"rgb8 must be uint8 of shape (H, W, 3), got {a.dtype} {a.shape}")
    H, W = a.shape[:2]
    rows = np.ascontiguousarray(a).reshape(H, W * 3)
    raw = np.empty((H, W * 3 + 1), dtype=np.uint8)
    raw[:, 0] = 2
    raw[0, 1:] = rows[0]
    np.subtract(rows[1:], rows[:-1], out=raw[1:, 1:])      # uint8: modulo 256
    _write_png_chunks(path, W, H, 8, zlib.compress(raw.tobytes(), level), text)


def _write_png_chunks(path, W: int, H: int, depth: int, idat: bytes, text) -> None:
    """The chunks of an RGB PNG of ``depth`` bits around its compressed image data."""
    parts = [b"\x89PNG\r\n\x1a\n",
             _chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, depth, 2, 0, 0, 0)),
             _chunk(b"sRGB", b"\x00")]
    for k, v in (text or {}).items():
        parts.append(_chunk(b"tEXt", k.encode("latin-1", "replace")[:79] + b"\x00"
                            + v.encode("latin-1", "replace")))
    parts.append(_chunk(b"IDAT", idat))
    parts.append(_chunk(b"IEND", b""))
    with open(path, "wb") as f:
        f.write(b"".join(parts))


def write_png16(path, rgb16: np.ndarray, text: dict[str, str] | None = None) -> None:
    """Write (H, W, 3) uint16 values as a 16-bit RGB PNG [PNG]: IHDR (bit depth 16,
    colour type 2), an sRGB chunk, tEXt chunks, one zlib IDAT (filter 0 per row), IEND."""
    a = np.asarray(rgb16)
    if a.ndim != 3 or a.shape[-1] != 3:
        raise ValueError(f"rgb16 must have shape (H, W, 3), got {a.shape}")
    H, W = a.shape[:2]
    rows = np.ascontiguousarray(a.astype(">u2")).view(np.uint8).reshape(H, W * 6)
    raw = np.concatenate([np.zeros((H, 1), dtype=np.uint8), rows], axis=1)
    _write_png_chunks(path, W, H, 16, zlib.compress(raw.tobytes(), 6), text)


def read_png16(path) -> np.ndarray:
    """Read an 8- or 16-bit RGB, non-interlaced PNG with filter type 0..4 rows (the files
    :func:`write_png16` and Pillow write) into (H, W, 3) uint16 (8-bit values scaled by
    257). For round-trip checks."""
    raw = Path(path).read_bytes()
    if raw[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError(f"{str(path)!r} is not a PNG file")
    pos, idat, ihdr = 8, [], None
    while pos < len(raw):
        n = struct.unpack(">I", raw[pos:pos + 4])[0]
        kind = raw[pos + 4:pos + 8]
        data = raw[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            ihdr = struct.unpack(">IIBBBBB", data)
        elif kind == b"IDAT":
            idat.append(data)
        pos += 12 + n
    W, H, depth, ctype, _, _, interlace = ihdr
    if ctype != 2 or depth not in (8, 16) or interlace:
        raise ValueError(f"{str(path)!r}: only non-interlaced 8/16-bit RGB PNG is supported")
    bpp = 3 * depth // 8
    stride = W * bpp
    data = np.frombuffer(zlib.decompress(b"".join(idat)), dtype=np.uint8).reshape(H, stride + 1)
    out = np.zeros((H, stride), dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.int32)
    for y in range(H):
        f, line = data[y, 0], data[y, 1:].astype(np.int32)
        cur = np.zeros(stride, dtype=np.int32)
        if f in (0, 2):
            cur = (line + (prev if f == 2 else 0)) & 0xFF
        else:
            for x in range(stride):
                a = cur[x - bpp] if x >= bpp else 0
                b = prev[x]
                c = prev[x - bpp] if x >= bpp else 0
                if f == 1:
                    pred = a
                elif f == 3:
                    pred = (a + b) // 2
                else:
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                cur[x] = (line[x] + pred) & 0xFF
        out[y] = cur
        prev = cur
    if depth == 16:
        return out.view(">u2").reshape(H, W, 3).astype(np.uint16)
    return out.reshape(H, W, 3).astype(np.uint16) * 257
