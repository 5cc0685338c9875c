"""Outputs for renderers and engines: environment maps in each tool's convention
(:mod:`skydome.export.envmap`, :mod:`skydome.export.conventions`), their GGX-prefiltered
mip levels (:mod:`skydome.export.prefilter`), the sun as a light
(:mod:`skydome.export.sun`) and LUT bakes with their GLSL look-ups
(:mod:`skydome.export.luts`, ``export/glsl``). Nothing heavy is imported here."""
