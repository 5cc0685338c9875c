"""``skydome render`` without typer's application (skydome.cli.render_fast): the command
lines it takes, those it leaves to typer, and the same output, errors and exit codes as the
typer command (the reference: the command line as typer parses it)."""

import os
import subprocess
import sys

import numpy as np
import pytest
import typer

from skydome.cli import app
from skydome.cli.render import render
from skydome.cli.render_fast import command_options, parse

OPTS = command_options(render)
TYPER = ("import sys; sys.argv = ['skydome'] + sys.argv[1:]; "
         "from skydome.cli import main; main()")


def test_options_are_those_typer_builds_for_the_command():
    """Every option typer's own command has (its click parameters), with the same names,
    flags and defaults: the fast parser reads them from the command's one declaration."""
    group = typer.main.get_command(app)
    cmd = group.commands["render"]
    typer_opts = {o: p for p in cmd.params for o in p.opts if o.startswith("--")}
    assert OPTS is not None and set(OPTS) == set(typer_opts)
    for opt, (name, kind, default) in OPTS.items():
        p = typer_opts[opt]
        assert p.name == name
        assert (kind == "flag") == bool(p.is_flag)
        if default is ...:
            assert p.required
        else:
            assert p.default == default, opt


def test_plain_command_lines_are_parsed_with_the_defaults():
    v = parse(["--sun-elevation", "-5.5", "--out", "x.png", "--no-sun", "--wavelengths",
               "8", "--exposure", "1e-3"], OPTS)
    assert v["sun_elevation"] == -5.5 and v["out"] == "x.png" and v["no_sun"] is True
    assert v["wavelengths"] == 8 and v["exposure"] == 1e-3
    assert v["model"] == "precomputed" and v["size"] == "512" and v["no_hunt"] is False
    assert v["sun_azimuth"] is None and v["sun_method"] == "spa" and v["bits"] == 8


@pytest.mark.parametrize("argv", [
    ["--out", "x.png", "--turbidity", "3"],            # a model's own option
    ["--out=x.png"],                                   # --name=value
    ["--out", "x.png", "--out", "y.png"],              # repeated
    ["--sun-elevation", "30"],                         # --out missing
    ["--out", "x.png", "--wavelengths", "8.0"],        # not plainly an integer
    ["--out", "x.png", "--sun-elevation", "nan"],      # not plainly a number
    ["--out", "x.png", "--sun-elevation", "1_0"],
    ["--out", "-x.png"],                               # a value that looks like an option
    ["--out", "x.png", "--help"],
    ["--out", "x.png", "extra"],                       # a positional argument
    ["--out"],                                         # a missing value
])
def test_other_command_lines_are_left_to_typer(argv):
    assert parse(argv, OPTS) is None


def test_a_models_own_options_are_passed_on_in_their_order():
    extra = []
    v = parse(["--out", "x.png", "--turbidity", "3", "--size", "40", "--ground-albedo", "0.2",
               "--turbidity", "4"], OPTS, extra)
    assert v is not None and v["size"] == "40" and v["out"] == "x.png"
    assert extra == ["--turbidity", "3", "--ground-albedo", "0.2", "--turbidity", "4"]


@pytest.mark.parametrize("argv", [
    ["--out", "x.png", "--turbidity"],                 # a missing value
    ["--out", "x.png", "--turbidity", "-3"],           # a value that looks like an option
    ["--out", "x.png", "--turbidity", "--size"],
    ["--out", "x.png", "--turbidity=3"],
    ["--out", "x.png", "--help", "x"],
    ["--out", "x.png", "--Turbidity", "3"],            # not a plain option name
    ["--out", "x.png", "-t", "3"],
])
def test_model_options_that_are_not_plain_are_left_to_typer(argv):
    assert parse(argv, OPTS, []) is None


def test_fast_path_runs_the_command_with_the_model_options(monkeypatch):
    """``fast_render`` calls the command's work with the model's options as typer's extra
    arguments (the list ``_render`` reads them from)."""
    from skydome.cli import _kit, render_fast

    seen = []
    monkeypatch.setattr(_kit, "_run", lambda func, *a: seen.append(a))
    assert render_fast.fast_render(["--model", "preetham1999", "--turbidity", "4", "--out",
                                    "x.png"]) == 0
    assert seen and seen[0][0] == ["--turbidity", "4"] and seen[0][1:3] == ("preetham1999",
                                                                            "x.png")


def _both(args, cwd):
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    fast = subprocess.run([sys.executable, "-m", "skydome", "render", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=600, env=env)
    slow = subprocess.run([sys.executable, "-c", TYPER, "render", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=600, env=env)
    return fast, slow


@pytest.mark.parametrize("args", [
    ["--sun-elevation", "95", "--out", "a.png"],
    ["--sun-elevation", "abc", "--out", "a.png"],
    ["--out", "a.txt"],
    ["--size", "0", "--out", "a.png"],
    ["--tonemap", "foo", "--out", "a.png"],
    ["--bits", "12", "--out", "a.png"],
    ["--wavelengths", "2", "--out", "a.png"],
    ["--exposure", "1", "--ev100", "3", "--out", "a.png"],
    ["--lat", "48.2", "--out", "a.png"],
    ["--out", "no-such-folder/a.png"],
    ["--out", "a.png", "--turbidity", "99"],          # a model's option out of its range
    ["--out", "a.png", "--no-such-option", "1"],      # a model option the model has not
    ["--model", "preetham1999", "--turbidity", "abc", "--out", "a.png"],
])
def test_bad_input_gives_the_typer_commands_line_and_exit_code(args, tmp_path):
    fast, slow = _both(args, tmp_path)
    assert fast.returncode == slow.returncode == 2, (fast.stderr, slow.stderr)
    assert fast.stderr == slow.stderr and fast.stdout == slow.stdout
    assert len(fast.stderr.strip().splitlines()) == 1 and fast.stderr.startswith("error: ")
    assert os.listdir(tmp_path) == []


@pytest.mark.parametrize("model_options", [[], ["--turbidity", "4.5"]])
def test_a_render_writes_the_same_picture_as_the_typer_command(tmp_path, model_options):
    from PIL import Image

    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    args = ["--model", "preetham1999", "--sun-elevation", "20", *model_options,
            "--sun-azimuth", "120", "--size", "40", "--out", "x.png"]
    fast = subprocess.run([sys.executable, "-m", "skydome", "render", *args], cwd=a,
                          capture_output=True, text=True, timeout=600)
    slow = subprocess.run([sys.executable, "-c", TYPER, "render", *args], cwd=b,
                          capture_output=True, text=True, timeout=600)
    assert fast.returncode == slow.returncode == 0, (fast.stderr, slow.stderr)
    # the line printed ends in the time taken
    assert fast.stdout.rsplit(",", 1)[0] == slow.stdout.rsplit(",", 1)[0]
    ia, ib = Image.open(a / "x.png"), Image.open(b / "x.png")
    assert np.array_equal(np.asarray(ia), np.asarray(ib)) and ia.text == ib.text


def test_entry_point_runs_the_fast_path_with_the_cyclic_collector_off(monkeypatch):
    """``skydome render ...`` tries the fast path first, with Python's cyclic collector off
    during it and on again afterwards; a command line the fast path leaves (None) goes to
    the typer application with the collector on."""
    import gc

    import skydome.__main__ as entry
    from skydome.cli import render_fast

    seen = []
    for code in (0, 2):
        monkeypatch.setattr(render_fast, "fast_render",
                            lambda argv, code=code: seen.append((argv, gc.isenabled())) or code)
        monkeypatch.setattr(sys, "argv", ["skydome", "render", "--out", "x.png"])
        with pytest.raises(SystemExit) as e:
            entry.main()
        assert e.value.code == code and gc.isenabled()
    assert seen == [(["--out", "x.png"], False)] * 2
    import skydome.cli.root as root

    monkeypatch.setattr(render_fast, "fast_render", lambda argv: None)
    monkeypatch.setattr(root, "main", lambda: seen.append(("typer", gc.isenabled())))
    entry.main()
    assert seen[-1] == ("typer", True)
