"""The skydome Blender add-on (folder ``skydome_sky``) and its packing.

The add-on itself (``skydome_sky/``: Blender UI code, importable only inside Blender) runs
:mod:`skydome.export.integrations.blender.bake` with skydome's own Python in a
subprocess. :func:`pack_addon` writes the installable zip: one top-level folder
``skydome_sky/`` holding ``__init__.py`` (with a legacy ``bl_info``) and
``blender_manifest.toml`` (the extension manifest), so that the same file installs as a
legacy add-on (Preferences > Add-ons > Install from Disk, ``bpy.ops.preferences.
addon_install``) and as an extension (``bpy.ops.extensions.package_install_files``) in
Blender 4.2 LTS, 4.5 LTS and 5.x.
"""

from __future__ import annotations

import zipfile
from pathlib import Path

__all__ = ["ADDON_MODULE", "addon_dir", "pack_addon"]

ADDON_MODULE = "skydome_sky"
_FILES = ("__init__.py", "blender_manifest.toml")


def addon_dir() -> Path:
    """The folder of the add-on's sources."""
    return Path(__file__).with_name(ADDON_MODULE)


def pack_addon(out_zip) -> Path:
    """Write the installable add-on zip to ``out_zip`` (a path ending in ``.zip``; written
    atomically, nothing left on failure); returns its path."""
    from skydome._io import atomic_file, check_output_file

    p = check_output_file(out_zip, (".zip",), name="add-on zip")
    src = addon_dir()
    with atomic_file(p) as tmp:
        with zipfile.ZipFile(tmp, "w", compression=zipfile.ZIP_DEFLATED) as z:
            for name in _FILES:
                z.write(src / name, f"{ADDON_MODULE}/{name}")
    return p
