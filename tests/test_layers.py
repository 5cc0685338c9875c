"""The layers hold one way, the merged Camera, the one contact-sheet function and render()'s
refusal of a model name.

The import graph is read from the source with ``ast``: every ``import`` and ``from ...
import`` at any depth (inside functions and methods too), relative imports resolved, and
``import skydome as sd`` resolved through the lazy names the package exports (``sd.render``
is an import of ``skydome.imaging``)."""

import ast
import math
import pkgutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import skydome
from skydome.camera import Camera

SRC = Path(__file__).resolve().parents[1] / "src"

# The layers, bottom first (DESIGN.md, docs/layers.md): a module may import its own layer and
# the layers below, never one above. A module belongs to the first entry that is its name or
# a package above it.
LAYERS = (
    # foundation: constants, input checks, data tables, atomic files, progress reports, the
    # generic Dask chunk runner, numba's start-up and its compilations' log, serial kernels
    # run on threads, numba's cache locators of the kernels
    ("skydome.constants", "skydome._validate", "skydome.data", "skydome._io",
     "skydome._progress", "skydome.distributed", "skydome._numba_start",
     "skydome._compile_log", "skydome._threads", "skydome._kernel_cache"),
    ("skydome.transport",),                       # the numerical core
    # the medium, the sun, colour science; the illuminance of planes (it integrates any
    # model, duck-typed; the analytic models use its quadrature nodes)
    ("skydome.spectra", "skydome.atmosphere", "skydome.sun", "skydome.illuminance"),
    ("skydome.camera",),                          # image geometry (the Projection protocol)
    ("skydome.models",),
    ("skydome.effects",),                         # the physics of the survey's section 5
    ("skydome.imaging",),                         # render(), SkyImage, writers, plots
    # outputs and data products built on images and models
    ("skydome.export", "skydome.daylighting", "skydome.viewer", "skydome.validation"),
    ("skydome.apps",),                            # drivers that make sets of files
    ("skydome.cli", "skydome.__main__"),          # the composition root
)
# `skydome` itself is the public facade: it imports its names lazily, on first use, and its
# importers are read through those names (see _graph), so it has no layer of its own.
FACADE = "skydome"

# Known breaks, each to be removed by a later change; delete an entry when its break is
# mended (the tests fail on an entry that no longer matches, so that none outlives its
# break). (importer, imported)
KNOWN_UPWARD: set[tuple[str, str]] = set()
# Edges cut before the search for cycles. (importer, imported)
KNOWN_CYCLE_EDGES: set[tuple[str, str]] = set()


def _modules(package: str) -> list[str]:
    root = SRC.joinpath(*package.split("."))
    return [package] + [f"{package}.{m.name}" for m in pkgutil.iter_modules([str(root)])
                        if not m.ispkg] + [
        f"{package}.{m.name}.{s.name}" for m in pkgutil.iter_modules([str(root)]) if m.ispkg
        for s in pkgutil.iter_modules([str(root / m.name)])]


@pytest.mark.parametrize("package", ["skydome.models", "skydome.effects", "skydome.transport",
                                     "skydome.atmosphere", "skydome.camera"])
def test_lower_layers_import_no_render_apps_or_plotting(package):
    mods = _modules(package) if SRC.joinpath(*package.split(".")).is_dir() else [package]
    code = ("import importlib, sys\n"
            f"for m in {mods!r}:\n    importlib.import_module(m)\n"
            "bad = sorted(m for m in sys.modules if m.startswith(('skydome.imaging', 'skydome.apps', "
            "'skydome.cli', 'matplotlib', 'PIL')))\nprint(','.join(bad))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env={"PYTHONPATH": str(SRC), "PATH": "/usr/bin:/bin"}, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.strip() == ""


def _modules_in(src: Path, root: str) -> dict:
    """{dotted module name: (file, is a package)} of every .py file of package ``root``."""
    mods = {}
    for f in sorted(src.joinpath(root).rglob("*.py")):
        parts = list(f.relative_to(src).with_suffix("").parts)
        is_pkg = parts[-1] == "__init__"
        mods[".".join(parts[:-1] if is_pkg else parts)] = (f, is_pkg)
    return mods


def _facade_names(init: Path) -> dict:
    """{name: module} of the names the facade package exports lazily: its ``_LAZY`` table and
    its ``_SUBMODULES`` (read from the source, not imported)."""
    names = {}
    root = init.parent.name
    for node in ast.walk(ast.parse(init.read_text())):
        if isinstance(node, ast.Assign) and len(node.targets) == 1 \
                and isinstance(node.targets[0], ast.Name):
            if node.targets[0].id == "_LAZY":
                names.update(ast.literal_eval(node.value))
            elif node.targets[0].id == "_SUBMODULES":
                names.update({n: f"{root}.{n}" for n in ast.literal_eval(node.value)})
    return names


def _existing(name: str, mods: dict) -> str:
    while name not in mods and "." in name:
        name = name.rsplit(".", 1)[0]
    return name


def import_graph(src: Path = SRC, root: str = "skydome") -> dict:
    """{module: set of the package's modules it imports}, from every Import and ImportFrom node
    at any depth of each file (relative imports resolved; an import of the facade ``root``
    resolved through the names used: ``sd.render`` or ``from skydome import render`` is an
    import of the module that defines ``render``; ``__version__`` is the facade's own)."""
    mods = _modules_in(src, root)
    lazy = _facade_names(src / root / "__init__.py")
    graph = {}
    for mod, (path, is_pkg) in mods.items():
        tree = ast.parse(path.read_text())
        targets, aliases = set(), set()
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.name == root:
                        aliases.add(a.asname or root)
                    elif a.name.startswith(root + "."):
                        targets.add(_existing(a.name, mods))
                        if a.asname is None:
                            aliases.add(root)   # `import skydome.x` binds `skydome`
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = mod.split(".") if is_pkg else mod.split(".")[:-1]
                    base = base[:len(base) - (node.level - 1)]
                    prefix = ".".join(base + ([node.module] if node.module else []))
                else:
                    prefix = node.module or ""
                if prefix != root and not prefix.startswith(root + "."):
                    continue
                for a in node.names:
                    if prefix == root:
                        if a.name in lazy:
                            targets.add(_existing(lazy[a.name], mods))
                        elif f"{root}.{a.name}" in mods:
                            targets.add(f"{root}.{a.name}")
                    else:
                        full = f"{prefix}.{a.name}"
                        targets.add(full if full in mods else _existing(prefix, mods))
        for node in ast.walk(tree):
            if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) \
                    and node.value.id in aliases and node.attr in lazy:
                targets.add(_existing(lazy[node.attr], mods))
        targets.discard(mod)
        targets.discard(root)
        graph[mod] = targets
    return graph


def layer_of(module: str, layers=LAYERS):
    for i, entries in enumerate(layers):
        if any(module == e or module.startswith(e + ".") for e in entries):
            return i
    return None


def upward_imports(graph: dict, layers=LAYERS, facade=FACADE) -> set:
    """(importer, imported) pairs where the imported module's layer is above the importer's."""
    return {(a, b) for a, bs in graph.items() if a != facade for b in bs
            if layer_of(b, layers) > layer_of(a, layers)}


def import_cycles(graph: dict, cut=frozenset()) -> list:
    """The strongly connected components of more than one module (Tarjan), with the edges in
    ``cut`` left out; each a sorted list."""
    index, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if (v, w) in cut:
                continue
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def test_the_import_walker_sees_imports_inside_functions(tmp_path):
    """The walker on a made-up package: an import inside a method, a relative import inside
    a function, a facade alias; the layer rule and the cycle search catch what they must."""
    pkg = tmp_path / "pk"
    (pkg / "low").mkdir(parents=True)
    (pkg / "__init__.py").write_text('_LAZY = {"Top": "pk.top"}\n_SUBMODULES = {"low"}\n')
    (pkg / "low" / "__init__.py").write_text("")
    (pkg / "low" / "a.py").write_text("import math\n\n\nclass A:\n    def f(self):\n"
                                      "        import pk as p\n        return p.Top\n")
    (pkg / "low" / "b.py").write_text("def g():\n    from . import a\n    from ..top import T\n")
    (pkg / "top.py").write_text("def h():\n    from pk.low.b import g\n    return g\n")
    graph = import_graph(tmp_path, "pk")
    assert graph["pk.low.a"] == {"pk.top"}
    assert graph["pk.low.b"] == {"pk.low.a", "pk.top"}
    assert graph["pk.top"] == {"pk.low.b"}
    layers = (("pk.low",), ("pk.top",))
    assert upward_imports(graph, layers, "pk") == {("pk.low.a", "pk.top"), ("pk.low.b", "pk.top")}
    assert import_cycles(graph) == [["pk.low.a", "pk.low.b", "pk.top"]]
    assert import_cycles(graph, {("pk.low.a", "pk.top"), ("pk.low.b", "pk.top")}) == []


def test_every_module_has_a_layer():
    graph = import_graph()
    assert [m for m in graph if m != FACADE and layer_of(m) is None] == []


def test_no_module_imports_a_layer_above_it():
    graph = import_graph()
    found = upward_imports(graph)
    assert sorted(found - KNOWN_UPWARD) == []
    assert sorted(KNOWN_UPWARD - found) == [], "fixed: remove these from KNOWN_UPWARD"


def test_no_import_cycle_among_the_modules():
    graph = import_graph()
    assert import_cycles(graph, KNOWN_CYCLE_EDGES) == []
    stale = sorted((a, b) for a, b in KNOWN_CYCLE_EDGES
                   if b not in graph.get(a, ()) or not any(
                       a in c and b in c for c in import_cycles(graph)))
    assert stale == [], "fixed: remove these from KNOWN_CYCLE_EDGES"


def test_only_the_command_line_imports_typer():
    """daylighting/, export/, validation/, viewer/ and the rest offer plain functions: only
    skydome.cli imports the command-line framework."""
    bad = []
    for mod, (path, _) in _modules_in(SRC, "skydome").items():
        if layer_of(mod) == len(LAYERS) - 1:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = ([a.name for a in node.names] if isinstance(node, ast.Import) else
                     [node.module or ""] if isinstance(node, ast.ImportFrom) else [])
            bad += [(mod, n) for n in names if n.split(".")[0] in ("typer", "click")]
    assert bad == []


def test_render_refuses_a_model_name_with_a_type_error():
    with pytest.raises(TypeError, match="'preetham1999'.*skydome.model"):
        skydome.render("preetham1999", skydome.Fisheye(8))
    with pytest.raises(TypeError, match="sky model"):
        skydome.render(object(), skydome.Fisheye(8))


def _enu(elevation_deg, azimuth_deg):
    el, az = math.radians(elevation_deg), math.radians(azimuth_deg)
    return np.array([math.cos(el) * math.sin(az), math.cos(el) * math.cos(az), math.sin(el)])


def test_camera_by_view_direction_matches_camera_by_points():
    a = Camera(fov_deg=50.0, azimuth_deg=30.0, elevation_deg=10.0, altitude_m=120.0)
    d = _enu(10.0, 30.0)
    b = Camera(8, 6, 50.0, position=(0.0, 0.0, 120.0), look_at=(d[0], d[1], 120.0 + d[2]), up=(0, 0, 1))
    dirs_a = a.ray_directions(8, 6)
    dirs_b, mask = b.directions()
    assert mask.all()
    np.testing.assert_allclose(dirs_a, dirs_b, atol=1e-12)
    assert (a.altitude_m, a.azimuth_deg) == (120.0, 30.0)
    assert b.elevation_deg == pytest.approx(10.0) and b.azimuth_deg == pytest.approx(30.0)


def test_camera_geometry_from_first_principles():
    """Pinhole geometry: the optical axis is the view direction; the rays through the middle
    of the left and right image edges are fov apart; the image top is towards the zenith;
    the pixel solid angles sum to the frustum's 4 asin(sin(a) sin(b)) for half-angles a, b."""
    cam = Camera(64, 32, 60.0, azimuth_deg=200.0, elevation_deg=5.0, altitude_m=10.0)
    np.testing.assert_allclose(cam.direction_from_pixel(16.0, 32.0), _enu(5.0, 200.0), atol=1e-12)
    left, right = cam.direction_from_pixel(16.0, 0.0), cam.direction_from_pixel(16.0, 64.0)
    assert math.degrees(math.acos(float(left @ right))) == pytest.approx(60.0, abs=1e-9)
    assert cam.direction_from_pixel(0.0, 32.0)[2] > cam.direction_from_pixel(32.0, 32.0)[2]
    a = math.radians(30.0)
    b = math.atan(math.tan(a) * 32 / 64)
    assert cam.solid_angles().sum() == pytest.approx(4 * math.asin(math.sin(a) * math.sin(b)), rel=1e-3)
    row, col = cam.pixel_from_direction(_enu(5.0, 200.0))
    assert (float(row), float(col)) == pytest.approx((16.0, 32.0))


def test_camera_refuses_bad_placements():
    with pytest.raises(ValueError, match="fov_deg"):
        Camera(8, 8, 180.0)
    with pytest.raises(ValueError, match="elevation_deg"):
        Camera(fov_deg=40.0, elevation_deg=90.0)
    with pytest.raises(ValueError, match="position"):
        Camera(8, 8, 40.0, position=(0, 0, 1))
    with pytest.raises(ValueError, match="not both"):
        Camera(8, 8, 40.0, position=(0, 0, 1), look_at=(0, 1, 1), azimuth_deg=3.0)
    with pytest.raises(ValueError, match="no image size"):
        Camera(fov_deg=40.0).directions()


def test_dobashi2002_and_render_share_one_camera_class():
    from skydome.effects import dobashi2002
    from skydome.imaging.projections import Projection

    assert dobashi2002.Camera is Camera
    assert issubclass(Camera, Projection)


def test_contact_sheet_layout(tmp_path):
    from PIL import Image

    from skydome.imaging.sheets import contact_sheet

    red = np.zeros((20, 20, 3))
    red[..., 0] = 1.0
    blue = np.zeros((10, 40, 3))
    blue[..., 2] = 1.0
    out = contact_sheet([(red, "a"), (blue, ["b", "second"]), (None, "missing")], tmp_path / "s.png",
                        cols=2, tile=40, background=(0, 0, 0))
    im = np.asarray(Image.open(out))
    # 2 columns of 40 px; 2 rows of (tallest image 20 px + two label lines of 14 px)
    assert im.shape == (2 * (20 + 28), 80, 3)
    assert tuple(im[10, 20]) == (255, 0, 0)          # red tile centred in its 40 px cell
    assert tuple(im[10, 60]) == (0, 0, 255)          # the 40x10 tile centred vertically
    assert tuple(im[2, 60]) == (0, 0, 0)
    assert [p.name for p in tmp_path.iterdir()] == ["s.png"]
    with pytest.raises(ValueError, match="tiles is empty"):
        contact_sheet([], tmp_path / "t.png")


def test_contact_sheet_letterbox_cells(tmp_path):
    # every cell the box (60 x 40): a square image scaled up to 40 x 40 and centred, a wide
    # one to 60 x 15; the last, shorter row centred; captions in a band under each box
    from PIL import Image

    from skydome.imaging.sheets import contact_sheet

    red = np.zeros((10, 10, 3))
    red[..., 0] = 1.0
    blue = np.zeros((10, 40, 3))
    blue[..., 2] = 1.0
    tiles = [(red, "a"), (blue, "b"), (red, "c")]
    out = contact_sheet(tiles, tmp_path / "s.png", cols=2, tile=(60, 40), line_height=10,
                        background=(0, 0, 0), letterbox=True)
    im = np.asarray(Image.open(out))
    assert im.shape == (2 * (40 + 10), 120, 3)
    assert tuple(im[20, 30]) == (255, 0, 0) and tuple(im[2, 30]) == (255, 0, 0)   # filled 40 px high
    assert tuple(im[20, 5]) == (0, 0, 0)                                           # letterbox bar
    assert tuple(im[20, 62]) == (0, 0, 255) and tuple(im[10, 90]) == (0, 0, 0)     # 60 x 15, centred
    assert tuple(im[50 + 20, 60]) == (255, 0, 0) and tuple(im[50 + 20, 20]) == (0, 0, 0)  # last row centred
