"""Daylighting at scale: weather files in, sky patches, sky matrices, Radiance matrix files out.

- :mod:`skydome.daylighting.weather`: EPW and TMY3 files (read by pvlib.iotools), the sun at
  each hour's midpoint.
- :mod:`skydome.daylighting.patches`: Tregenza and Reinhart MF:n sky patches (Radiance's
  geometry and order), solid angles, quadrature nodes over each patch.
- :mod:`skydome.daylighting.skymatrix`: hours x patches sky matrices (perez1993 through one
  vectorised kernel call over all hours) and a separate sun matrix.
- :mod:`skydome.daylighting.radiance_io`: Radiance matrix files (ascii, float, double) and .npy.

Nothing here is imported by ``import skydome``.
"""
