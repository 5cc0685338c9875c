"""Outputs for renderers and engines: environment maps in each tool's convention
(:mod:`skydome.export.envmap`, :mod:`skydome.export.conventions`) and the sun as a light
(:mod:`skydome.export.sun`). Nothing heavy is imported here."""
