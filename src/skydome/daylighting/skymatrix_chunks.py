"""The annual Perez (1993) sky matrix in chunks of hours on Dask: the chunks for the generic
runner :func:`skydome.distributed.run_chunks`, and the whole job
(:func:`distributed_sky_matrix`), resumable as every chunked job is there.
"""

from __future__ import annotations

import numpy as np

from skydome.distributed import (CONNECT_TIMEOUT_S, Chunk, assemble_chunks, check_scheduler,
                                 run_chunks)

__all__ = ["sky_matrix_chunks", "distributed_sky_matrix", "split_sun"]


def _sky_chunk(dni, dhi, sun, doy, td, rho, kwargs):
    """The chunk's sky matrix (h, P, C); with ``sun="separate"`` its sun matrix is appended
    as one more row per hour (h, P + 1, C), split off again by :func:`split_sun`."""
    from skydome.daylighting.skymatrix import perez_sky_matrix

    # Writable copies: a worker receives its arguments as read-only arrays, for which numba
    # compiles a second specialisation of the kernels whose floating-point contraction can
    # differ in the last bit; the same specialisation everywhere keeps chunks bit-identical
    # to a serial run.
    dni, dhi, sun, doy, td, rho = (np.array(a) if isinstance(a, np.ndarray) else a
                                   for a in (dni, dhi, sun, doy, td, rho))
    m = perez_sky_matrix(dni, dhi, sun, doy, dew_point_c=td, ground_reflectance=rho, **kwargs)
    if m.sun is None:
        return m.sky
    return np.concatenate([m.sky, m.sun[:, None, :].astype(m.sky.dtype)], axis=1)


def split_sun(matrix: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(sky (h, P, C), sun (h, C)) of an assembled ``sun="separate"`` matrix (h, P + 1, C)."""
    return matrix[:, :-1, :], np.ascontiguousarray(matrix[:, -1, :])


def sky_matrix_chunks(weather, chunk_hours: int = 730, sun_position: str = "spa",
                      ground_reflectance=0.2, **kwargs) -> list[Chunk]:
    """The chunks of an annual perez1993 sky matrix: ``chunk_hours`` hours each, keyed by
    their first and last hour (``h00000-00729``); ``kwargs`` go to perez_sky_matrix."""
    from skydome._validate import check_int

    chunk_hours = check_int("chunk_hours", chunk_hours, 1, None)
    sd = weather.spa_sun_directions() if sun_position == "spa" else weather.radiance_sun_directions()
    n = len(weather)
    td = np.full(n, 11.0) if weather.dew_point_c is None else np.where(
        np.isfinite(weather.dew_point_c), weather.dew_point_c, 11.0)
    rho = np.broadcast_to(np.asarray(ground_reflectance, dtype=np.float64), (n,))
    out = []
    for a in range(0, n, chunk_hours):
        b = min(n, a + chunk_hours)
        out.append(Chunk(f"h{a:05d}-{b - 1:05d}", _sky_chunk,
                         (weather.dni[a:b], weather.dhi[a:b], sd[a:b], weather.day_of_year[a:b],
                          td[a:b], rho[a:b].copy(), dict(kwargs))))
    return out


def distributed_sky_matrix(weather, folder, *, chunk_hours: int = 730,
                           scheduler: str | None = None, n_workers: int = 2, client=None,
                           progress: bool = False,
                           connect_timeout_s: float = CONNECT_TIMEOUT_S, **kwargs):
    """Annual sky matrix computed in chunks on Dask; returns (matrix (hours, patches, comp),
    JobReport). Rerunning with the same ``folder`` reuses the verified chunks. With
    ``sun="separate"`` the matrix holds the sun matrix as one more row (hours, patches + 1,
    comp): :func:`split_sun` separates them. ``scheduler`` is checked before any work and
    ``connect_timeout_s`` bounds the wait for it (:func:`skydome.distributed.run_chunks`)."""
    check_scheduler(scheduler)
    chunks = sky_matrix_chunks(weather, chunk_hours=chunk_hours, **kwargs)
    rep = run_chunks(chunks, folder, scheduler=scheduler, n_workers=n_workers, client=client,
                     progress=progress, connect_timeout_s=connect_timeout_s)
    return assemble_chunks(folder, [c.key for c in chunks]), rep
