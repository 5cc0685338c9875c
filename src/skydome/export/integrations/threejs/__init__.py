"""skydome's precomputed and fitted skies in three.js: the ES module ``skydome-sky.js``, its
example page ``example.html`` and the shaders it runs, ``export/glsl/precomputed.glsl`` and
``export/glsl/fitted.glsl`` (luts.json's model and format pick one).

:func:`write_threejs` copies them into a folder (the shaders from their one source in
``skydome.export.glsl``), ready to be served beside npm's ``three`` and a bake of
``skydome export luts --model precomputed --format bin`` or ``--model fitted --format bin``
(docs/rendering.md, "three.js")."""

from __future__ import annotations

from pathlib import Path

__all__ = ["FILES", "write_threejs"]

_HERE = Path(__file__).parent
_GLSL = _HERE.parents[1] / "glsl"

#: The files :func:`write_threejs` writes, with their sources.
FILES = {"skydome-sky.js": _HERE / "skydome-sky.js", "example.html": _HERE / "example.html",
         "precomputed.glsl": _GLSL / "precomputed.glsl",
         "fitted.glsl": _GLSL / "fitted.glsl"}


def write_threejs(folder) -> list[Path]:
    """Write the three.js module, its example page and the shaders into ``folder`` (created
    complete, or its files replaced; :func:`skydome._io.atomic_folder`). Returns the paths.

    Serve ``folder`` next to npm's ``three`` package (as ``three/``) and a precomputed or
    fitted LUT bake in ``.bin`` (as ``luts/``): ``example.html`` imports ``../three/build/
    three.module.js`` and reads ``../luts/`` unless its URL says ``?luts=...``."""
    from skydome._io import atomic_folder, check_output_folder

    folder = check_output_folder(folder)
    written = []
    with atomic_folder(folder) as tmp:
        for name, src in FILES.items():
            (tmp / name).write_bytes(src.read_bytes())
            written.append(folder / name)
    return written
