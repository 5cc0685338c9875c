"""``skydome export envmap`` without typer's application (skydome.cli.render_fast.
fast_export_envmap): the command lines it takes, those it leaves to typer, and the same
output, errors and exit codes as the typer command (the reference: the command line as typer
parses it)."""

import os
import subprocess
import sys

import pytest
import typer

from skydome.cli import app
from skydome.cli.export import envmap
from skydome.cli.render_fast import command_options, parse

OPTS = command_options(envmap)
TYPER = ("import sys; sys.argv = ['skydome'] + sys.argv[1:]; "
         "from skydome.cli import main; main()")


def test_options_are_those_typer_builds_for_the_command():
    """Every option typer's own command has (its click parameters), with the same names,
    flags and defaults: the fast parser reads them from the command's one declaration."""
    group = typer.main.get_command(app)
    cmd = group.commands["export"].commands["envmap"]
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


def test_model_options_are_passed_on_in_order():
    extra = []
    v = parse(["--model", "hosek_wilkie2012", "--turbidity", "3", "--size", "4096x2048",
               "--half", "--ground-albedo", "0.3", "--albedo", "0.1", "--out", "x.exr"],
              OPTS, extra)
    assert extra == ["--turbidity", "3", "--albedo", "0.1"]
    assert v["model"] == "hosek_wilkie2012" and v["half"] is True and v["out"] == "x.exr"
    assert v["ground_albedo"] == 0.3 and v["size"] == "4096x2048" and v["mips"] == 0
    assert v["convention"] == "skydome" and v["wavelengths"] == 16 and v["units"] is None


@pytest.mark.parametrize("argv", [
    ["--out", "x.exr", "--turbidity", "-3"],           # a model option's value like an option
    ["--out", "x.exr", "--turbidity"],                 # a missing value
    ["--out", "x.exr", "--Turbidity", "3"],            # not a plain option name
    ["--out=x.exr"],                                   # --name=value
    ["--out", "x.exr", "--out", "y.exr"],              # repeated
    ["--size", "64x32"],                               # --out missing
    ["--out", "x.exr", "--mips", "2.0"],               # not plainly an integer
    ["--out", "x.exr", "--help", "x"],
    ["--out", "x.exr", "extra"],                       # a positional argument
])
def test_other_command_lines_are_left_to_typer(argv):
    assert parse(argv, OPTS, []) is None


def _both(args, cwd):
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    fast = subprocess.run([sys.executable, "-m", "skydome", "export", "envmap", *args],
                          cwd=cwd, capture_output=True, text=True, timeout=600, env=env)
    slow = subprocess.run([sys.executable, "-c", TYPER, "export", "envmap", *args], cwd=cwd,
                          capture_output=True, text=True, timeout=600, env=env)
    return fast, slow


@pytest.mark.parametrize("args", [
    ["--model", "preetham1999", "--turbidity", "0.5", "--out", "a.exr"],
    ["--model", "preetham1999", "--colour", "3", "--out", "a.exr"],
    ["--model", "no-such-model", "--out", "a.exr"],
    ["--model", "preetham1999", "--size", "0", "--out", "a.exr"],
    ["--model", "preetham1999", "--sun-elevation", "95", "--out", "a.exr"],
    ["--model", "preetham1999", "--half", "--sun-in-map", "--out", "a.exr"],
    ["--model", "preetham1999", "--out", "a.png"],
    ["--model", "preetham1999", "--out", "no-such-folder/a.exr"],
])
def test_bad_input_gives_the_typer_commands_line_and_exit_code(args, tmp_path):
    fast, slow = _both(args, tmp_path)
    assert fast.returncode == slow.returncode == 2, (fast.stderr, slow.stderr)
    assert fast.stderr == slow.stderr and fast.stdout == slow.stdout
    assert len(fast.stderr.strip().splitlines()) == 1 and fast.stderr.startswith("error: ")
    assert os.listdir(tmp_path) == []


def test_a_map_is_written_as_by_the_typer_command(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir()
    b.mkdir()
    args = ["--model", "hosek_wilkie2012", "--turbidity", "3", "--sun-elevation", "20",
            "--size", "64x32", "--half", "--out", "x.exr"]
    fast = subprocess.run([sys.executable, "-m", "skydome", "export", "envmap", *args],
                          cwd=a, capture_output=True, text=True, timeout=600)
    slow = subprocess.run([sys.executable, "-c", TYPER, "export", "envmap", *args], cwd=b,
                          capture_output=True, text=True, timeout=600)
    assert fast.returncode == slow.returncode == 0, (fast.stderr, slow.stderr)
    # the line printed ends in the time taken
    assert fast.stdout.rsplit(",", 1)[0] == slow.stdout.rsplit(",", 1)[0]
    for name in ("x.exr", "x.sun.json"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name


def test_entry_point_runs_the_fast_path_with_the_cyclic_collector_off(monkeypatch):
    """``skydome export envmap ...`` tries the fast path first, with Python's cyclic
    collector off during it and on again afterwards; a command line the fast path leaves
    (None) goes to the typer application with the collector on."""
    import gc

    import skydome.__main__ as entry
    from skydome.cli import render_fast

    seen = []
    for code in (0, 2):
        monkeypatch.setattr(render_fast, "fast_export_envmap",
                            lambda argv, code=code: seen.append((argv, gc.isenabled())) or code)
        monkeypatch.setattr(sys, "argv", ["skydome", "export", "envmap", "--out", "x.exr"])
        with pytest.raises(SystemExit) as e:
            entry.main()
        assert e.value.code == code and gc.isenabled()
    assert seen == [(["--out", "x.exr"], False)] * 2
    import skydome.cli.root as root

    monkeypatch.setattr(render_fast, "fast_export_envmap", lambda argv: None)
    monkeypatch.setattr(root, "main", lambda: seen.append(("typer", gc.isenabled())))
    entry.main()
    assert seen[-1] == ("typer", True)
