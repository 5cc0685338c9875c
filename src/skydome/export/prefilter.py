"""Prefiltered mip levels of an environment map for image-based lighting: the specular
part of the split-sum approximation with the GGX distribution [Kar13].

Level k of n holds, for each direction r of its texels, the map filtered with the GGX lobe
of roughness ``r_k = k / (n - 1)`` (alpha = r_k^2, as in [Kar13]) under [Kar13]'s
assumption n = v = r:

    P(r) = sum_p L_p D(h_p) max(r . l_p, 0) dOmega_p / sum_p D(h_p) max(r . l_p, 0) dOmega_p

with h_p = (r + l_p) / |r + l_p|, D(h) = alpha^2 / (pi ((r . h)^2 (alpha^2 - 1) + 1)^2)
([Wal07] eq. 33) and the sum over the map's pixels p (direction l_p, solid angle
dOmega_p). That is the integral that [Kar13]'s importance-sampled loop estimates (its
samples l have the density D(h) (n . h) / (4 (v . h)) = D(h) / 4 for n = v, weighted by
n . l); here it is evaluated over every pixel instead of sampled, so it has no noise.
Level 0 (roughness 0, a mirror) is the map itself.

Lat-long maps: a texel row is a ring of fixed zenith angle and the lobe depends only on
the azimuth difference, so for each output row the sum over a source row is a circular
convolution in azimuth, done with FFTs (exact, the same sum as brute force). For coarse
levels the source is the map averaged over 2 x 2 texel blocks (solid-angle weighted)
as long as its texels stay under an eighth of the lobe's width (alpha rad), never coarser
than four times the level's own texels. Cube maps: the faces are resampled onto a lat-long
source (4 N x 2 N, 2 x 2 samples per texel), filtered as above at twice the level's
resolution and looked up bilinearly at each face texel's direction.

References
----------
.. [Kar13] B. Karis, "Real Shading in Unreal Engine 4", SIGGRAPH 2013 course notes
   (Physically Based Shading in Theory and Practice): the split sum, PrefilterEnvMap
   (n = v = r, weights n . l), roughness -> alpha = roughness^2.
.. [Wal07] B. Walter, S. Marschner, H. Li, K. Torrance, "Microfacet Models for Refraction
   through Rough Surfaces", EGSR 2007, eq. 33 (the GGX distribution).
"""

from __future__ import annotations

import numpy as np

__all__ = ["ggx_weight", "prefilter_latlong", "prefiltered_mips", "mip_roughness",
           "check_mip_levels"]


def mip_roughness(levels: int) -> np.ndarray:
    """Perceptual roughness of each of ``levels`` mip levels: k / (levels - 1)."""
    return np.linspace(0.0, 1.0, levels)


def check_mip_levels(levels, height: int, name: str = "mip_levels") -> int:
    """ValueError unless ``levels`` is an integer in [2, 16] with the last level at least
    4 texels high (lat-long) / wide (cube faces)."""
    from skydome._validate import check_int

    levels = check_int(name, levels, 2, 16)
    if height >> (levels - 1) < 4:
        top = max(2, int(np.log2(max(height, 1))) - 1)
        raise ValueError(f"{name} = {levels} is out of range for a map {height} texels "
                         f"high: valid [2, {top}] (the last level must be >= 4 texels)")
    return levels


def ggx_weight(cos_angle, alpha: float) -> np.ndarray:
    """D(h) max(r . l, 0) of [Kar13]'s prefilter (n = v = r) for directions l at angle
    acos(``cos_angle``) from r; D of [Wal07] eq. 33 with (r . h)^2 = (1 + r . l) / 2."""
    c = np.asarray(cos_angle, dtype=np.float64)
    a2 = alpha * alpha
    nh2 = 0.5 * (1.0 + c)
    D = a2 / (np.pi * (nh2 * (a2 - 1.0) + 1.0) ** 2)
    return np.where(c > 0.0, D * c, 0.0)


def _band_solid_angles(H: int, W: int) -> np.ndarray:
    edges = np.cos(np.pi * np.arange(H + 1) / H)
    return (edges[:-1] - edges[1:]) * (2.0 * np.pi / W)


def _downsample(img: np.ndarray) -> np.ndarray:
    """2 x 2 blocks of a lat-long image averaged with solid-angle weights (energy kept)."""
    H, W = img.shape[:2]
    w = _band_solid_angles(H, W)[:, None, None]
    num = (img * w).reshape(H // 2, 2, W // 2, 2, -1).sum(axis=(1, 3))
    den = np.broadcast_to(w, (H, W, 1)).reshape(H // 2, 2, W // 2, 2, 1).sum(axis=(1, 3))
    return num / den


def prefilter_latlong(image, roughness: float, out_width: int, out_height: int,
                      source=None) -> np.ndarray:
    """GGX-prefiltered lat-long map (out_height, out_width, 3) of a lat-long ``image``
    (H, W, 3) whose rows are rings of zenith angle pi (i + 0.5) / H and whose columns are
    even steps of azimuth (any convention's lat-long layout); ``W`` must be a multiple of
    ``out_width`` (texel centres then coincide in azimuth). ``source`` overrides the image
    summed over (same layout, coarser), see the module notes."""
    img = np.asarray(image if source is None else source, dtype=np.float64)
    Hs, Ws = img.shape[:2]
    if Ws % out_width or Ws < out_width:
        raise ValueError(f"out_width = {out_width} must divide the source width {Ws}")
    if roughness <= 0.0:
        raise ValueError("roughness = 0 is the map itself (a mirror): give roughness in (0, 1]")
    alpha = float(roughness) ** 2                             # [Kar13] alpha = roughness^2
    s = Ws // out_width
    th_s = np.pi * (np.arange(Hs) + 0.5) / Hs
    th_o = np.pi * (np.arange(out_height) + 0.5) / out_height
    omega = _band_solid_angles(Hs, Ws)                        # (Hs,)
    # azimuth offsets of the source columns from output column 0 (module notes)
    dphi = 2.0 * np.pi * (0.5 * s - 0.5 + np.arange(Ws)) / Ws
    cos_dphi = np.cos(dphi)
    # the source rows' spectra, frequency first: (Ws/2+1, Hs, channels)
    F = np.ascontiguousarray(np.fft.rfft(img * omega[:, None, None], axis=1).transpose(1, 0, 2))
    out = np.empty((out_height, out_width, img.shape[2]))
    for i, t in enumerate(th_o):
        c = (np.cos(t) * np.cos(th_s))[:, None] + (np.sin(t) * np.sin(th_s))[:, None] * cos_dphi
        g = ggx_weight(c, alpha)                              # (Hs, Ws), g[j, m]
        # out(c) = sum_j sum_c' g_j((s c - c') mod Ws) S_j(c'): a circular convolution per
        # source row j, summed over j in frequency space (one batched product per frequency)
        G = np.fft.rfft(g, axis=1)                            # (Hs, Ws/2+1)
        num_hat = np.matmul(G.T[:, None, :], F)[:, 0, :]      # (Ws/2+1, channels)
        num = np.fft.irfft(num_hat, n=Ws, axis=0)[::s]
        den = g.sum(axis=1) @ omega
        out[i] = num / den
    return np.maximum(out, 0.0)


def _source_for(image: np.ndarray, alpha: float, out_width: int) -> np.ndarray:
    """The coarsest 2 x 2 average of ``image`` whose texels stay under alpha / 8 rad and
    at least four times as fine as the output (module notes)."""
    src = image
    while (src.shape[1] // 2 >= 4 * out_width and src.shape[0] % 2 == 0
           and src.shape[1] % 2 == 0 and 2.0 * np.pi / (src.shape[1] // 2) <= alpha / 8.0):
        src = _downsample(src)
    return src


def _cube_to_latlong(env, W: int, H: int) -> np.ndarray:
    """A lat-long image (H, W, 3) in skydome's own convention of a cube ``env``: the mean of
    2 x 2 nearest-texel samples per texel."""
    from skydome.export.envmap import FACES, MapProjection

    proj = MapProjection("skydome", W, H)
    out = np.zeros((H, W, 3))
    rows, cols = np.mgrid[0:H, 0:W].astype(np.float64)
    for dr in (0.25, 0.75):
        for dc in (0.25, 0.75):
            d = proj.direction_from_pixel(rows + dr, cols + dc)
            for f in FACES:
                p = env.projections[f]
                r, c = p.pixel_from_direction(d)
                ok = np.isfinite(r) & np.isfinite(c)
                n = p.height
                ri = np.clip(r[ok].astype(int), 0, n - 1)
                ci = np.clip(c[ok].astype(int), 0, n - 1)
                out[ok] += 0.25 * env.images[f][ri, ci]
    return out


def _bilinear_latlong(img: np.ndarray, d_enu: np.ndarray) -> np.ndarray:
    """Bilinear look-up (wrapping in azimuth) of a skydome-convention lat-long image."""
    from skydome.export.envmap import MapProjection

    H, W = img.shape[:2]
    r, c = MapProjection("skydome", W, H).pixel_from_direction(d_enu)
    y = np.clip(r - 0.5, 0.0, H - 1.0)
    x = c - 0.5
    y0 = np.minimum(np.floor(y).astype(int), H - 2)
    fy = (y - y0)[..., None]
    x0 = np.floor(x).astype(int)
    fx = (x - x0)[..., None]
    x1 = (x0 + 1) % W
    x0 = x0 % W
    return ((1 - fy) * ((1 - fx) * img[y0, x0] + fx * img[y0, x1])
            + fy * ((1 - fx) * img[y0 + 1, x0] + fx * img[y0 + 1, x1]))


def prefiltered_mips(env, levels: int = 6, progress=None) -> list:
    """GGX-prefiltered mip chain of an :class:`~skydome.export.envmap.EnvironmentMap` in
    the lat-long or a cube layout: a list of ``levels`` EnvironmentMaps in the map's
    convention and layout, level k half the size of level k - 1, roughness
    :func:`mip_roughness` (level 0 is ``env`` itself). ``progress(done, total)`` per level."""
    from skydome.export.envmap import (_CUBE_LAYOUTS, FACES, CubeFaceProjection,
                                       EnvironmentMap, MapProjection)

    cube = env.layout in _CUBE_LAYOUTS
    if not cube and env.layout != "latlong":
        raise ValueError(f"layout = {env.layout!r}: prefiltered mips are made for latlong and "
                         f"the cube layouts ({', '.join(_CUBE_LAYOUTS)})")
    size = env.images["+X"].shape[0] if cube else env.images["map"].shape[0]
    levels = check_mip_levels(levels, size)
    rough = mip_roughness(levels)
    if cube:
        N = size
        base = _cube_to_latlong(env, 4 * N, 2 * N)
    else:
        base = env.images["map"]
    out = [env]
    for k in range(1, levels):
        alpha = rough[k] ** 2
        meta = dict(env.metadata, mip_level=k, roughness=float(rough[k]), alpha=float(alpha),
                    prefilter="GGX split-sum specular, n = v = r (Karis 2013)")
        if cube:
            n = max(1, N >> k)
            w_o = 8 * n                                 # twice the faces' resolution
            ll = prefilter_latlong(base, rough[k], w_o, w_o // 2,
                                   source=_source_for(base, alpha, w_o))
            projs = {f: CubeFaceProjection(env.convention, f, n) for f in FACES}
            imgs = {}
            for f, p in projs.items():
                d, _ = p.directions()
                imgs[f] = _bilinear_latlong(ll, d)
        else:
            H, W = base.shape[:2]
            h, w = max(1, H >> k), max(1, W >> k)
            imgs = {"map": prefilter_latlong(base, rough[k], w, h,
                                             source=_source_for(base, alpha, w))}
            projs = {"map": MapProjection(env.convention, w, h)}
        out.append(EnvironmentMap(imgs, projs, env.convention, env.layout, meta,
                                  units=env.units))
        if progress is not None:
            progress(k, levels - 1)
    return out


def mip_paths(path, levels: int) -> list:
    """File of each level k >= 1 beside ``path``: ``<stem>_mip<k><suffix>``."""
    from pathlib import Path

    p = Path(path)
    return [p.with_name(f"{p.stem}_mip{k}{p.suffix}") for k in range(1, levels)]


def write_mips(mips, path, half: bool = False) -> list:
    """Write levels 1.. of ``mips`` (from :func:`prefiltered_mips`) beside the level-0 file
    ``path`` as ``<stem>_mip<k><suffix>`` (each in the map's layout; ``faces``: six files
    per level) and ``<stem>.mips.json`` (roughness, alpha and file of every level). All or
    nothing: on a failure the files already written are removed. Returns the paths."""
    import json
    from pathlib import Path

    from skydome._io import atomic_write

    p = Path(path)
    written = []
    try:
        for lev, target in zip(mips[1:], mip_paths(p, len(mips))):
            written += lev.write(target, half=half)
        doc = {"prefilter": "GGX specular, split sum with n = v = r (Karis 2013, "
                            "PrefilterEnvMap), integrated over every texel of the map",
               "roughness_to_alpha": "alpha = roughness^2",
               "convention": mips[0].convention.name, "layout": mips[0].layout,
               "levels": [{"level": k, "roughness": float(r), "alpha": float(r * r),
                           "file": (p if k == 0 else mip_paths(p, len(mips))[k - 1]).name,
                           "size": list(next(iter(m.images.values())).shape[:2])}
                          for k, (m, r) in enumerate(zip(mips, mip_roughness(len(mips))))]}
        js = p.with_name(p.stem + ".mips.json")
        atomic_write(js, lambda tmp: Path(tmp).write_text(json.dumps(doc, indent=2)))
        written.append(js)
    except BaseException:
        for w in written:
            Path(w).unlink(missing_ok=True)
        raise
    return written
