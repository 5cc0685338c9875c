"""How far the ``fitted`` model's coefficients can be compressed along the wavelength.

    python tools/fitted_spectral_rank.py OUT --rank K [--coefficients FILE]
    python tools/fitted_accuracy.py HELDOUT --coefficients OUT

The coefficients are, per atmosphere, sun-elevation node, altitude and table wavelength,
the 32 (sky) and 12 (ground) coefficients of the angular basis of its sun node
(skydome/models/fitted/_coefficients.py): 52 table wavelengths (49 up to the seventh
file). Along the wavelength they vary smoothly but for the gas bands. A file stores them
per wavelength, or as spectral terms (``tools/fit_fitted.py --spectral-rank K``, the
shipped file: K = 24); either is read here, expanded to the table wavelengths. This tool
writes a file whose coefficients are the truncated singular value decomposition along the
wavelength (per sun node, over every atmosphere, altitude and coefficient: the rows; the
mean row removed first) kept to its first K terms: what a file holding K coefficients per
node instead of one per wavelength, and per sun node K spectral vectors of one value per
wavelength, would give. The file
written is for measuring (its coefficients are stored in float32, already expanded to the
table wavelengths, which the model reads like any other file): ``tools/fitted_accuracy.py
--coefficients OUT`` on the held-out grid gives its errors beside the shipped file's.

It prints the relative RMS of the truncation per array and the size the coefficients
would take stored as K amplitudes in float16 (a float32 scale per row, as ``fit_fitted.py
--float16`` stores them) with the spectral vectors and means in float32. The measured
ranks: docs/models.md, "fitted", "The spectral terms".
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

KEYS = ("coef_sky", "coef_ground")


def truncate(C: np.ndarray, rank: int) -> tuple[np.ndarray, float]:
    """(the coefficients C (A, B, E, H, W, T) with their wavelength axis W truncated to
    ``rank`` spectral terms per sun node E (the model's own factorisation,
    ``_coefficients.spectral_factors``, expanded back), relative RMS of the change)."""
    from skydome.models.fitted._coefficients import spectral_factors

    amp, spec, mean, rel = spectral_factors(C, rank)
    return _expand(amp, spec, mean).astype(C.dtype), rel


def _expand(amp, spec, mean) -> np.ndarray:
    """(A, B, E, H, W, T) from amplitudes (A, B, E, H, K, T) and per sun node E spectral
    vectors (E, K, W) and means (E, W)."""
    from skydome.models.fitted._coefficients import expand_spectral

    return expand_spectral(amp, spec[None, None, :, None], mean[None, None, :, None])


def expanded(arrays: dict, key: str) -> np.ndarray:
    """The coefficients ``key`` (A, B, E, H, W, T) in float32 from a file's arrays (popped
    from ``arrays``): stored per wavelength (float32, or float16 with a scale per row), or
    as spectral terms (``tools/fit_fitted.py --spectral-rank``: mean[e] + sum_k amp[k]
    spec[e, k])."""
    amp = arrays.pop(key + "_amp", None)
    if amp is None:
        C = arrays.pop(key).astype(np.float32)
        scale = arrays.pop(key + "_scale", None)
        return C if scale is None else C * scale[..., None]
    amp = amp.astype(np.float32)
    scale = arrays.pop(key + "_amp_scale", None)
    if scale is not None:
        amp = amp * scale[..., None]
    spec, mean = arrays.pop(key + "_spec"), arrays.pop(key + "_spec_mean")
    return _expand(amp, spec, mean).astype(np.float32)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out")
    ap.add_argument("--rank", type=int, required=True)
    ap.add_argument("--coefficients", default=None,
                    help="coefficient file to compress (default: the package's)")
    a = ap.parse_args(argv)
    from skydome._io import atomic_write
    from skydome.models.fitted import _coefficients

    src = Path(a.coefficients) if a.coefficients is not None else _coefficients.COEFFICIENT_FILE
    if not src.is_file():
        print(f"error: --coefficients = {src} is not a file", file=sys.stderr)
        return 2
    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    n_wl = int(arrays["wavelengths_nm"].size)
    if not 1 <= a.rank <= n_wl:
        print(f"error: --rank = {a.rank} is out of range [1, {n_wl}] (the file's table "
              "wavelengths)", file=sys.stderr)
        return 2
    n_bytes = 0
    for key in KEYS:
        C = expanded(arrays, key)
        R, rel = truncate(C, a.rank)
        arrays[key] = R
        A, B, E, H, W, T = C.shape
        amp = A * B * E * H * a.rank * T * 2 + A * B * E * H * a.rank * 4
        vec = E * (a.rank + 1) * W * 4
        n_bytes += amp + vec
        print(f"{key}: rank {a.rank} of {W}: relative RMS of the truncation {rel:.2e}; "
              f"stored so {(amp + vec) / 1e6:.2f} MB (per wavelength in float16: "
              f"{C.size * 2 / 1e6:.2f} MB)")
    print(f"coefficients at rank {a.rank}: {n_bytes / 1e6:.2f} MB")
    atomic_write(a.out, lambda tmp: np.savez(tmp, **arrays), suffix=".npz")
    print(f"wrote {a.out} (for measuring: tools/fitted_accuracy.py HELDOUT --coefficients "
          f"{a.out})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
