"""No command or option of the command line is lost: the whole surface of ``skydome`` (every
group, every command, every option's spellings, whether it is required, its default) is
compared with tests/data/cli_surface.json, written from the command line as it stood before
the commands were gathered into the ``skydome.cli`` package; and every group's and command's
``--help`` lists its commands and options."""

import json
from pathlib import Path

import pytest
from typer.testing import CliRunner

SNAPSHOT = Path(__file__).parent / "data" / "cli_surface.json"


def _default(param):
    d = param.default
    if callable(d):
        return "<callable>"
    if isinstance(d, tuple):
        d = list(d)
    return d if d is None or isinstance(d, (bool, int, float, str, list)) else repr(d)


def surface(command, path=()) -> dict:
    """{'skydome cmd sub': {'commands': [...]} or {'options': {...}}} for every group and
    command under ``command`` (a click command)."""
    key = " ".join(("skydome",) + path)
    opts = {}
    for p in command.params:
        if p.name == "help" or not getattr(p, "opts", None):
            continue
        kind = "argument" if p.param_type_name == "argument" else (
            "flag" if getattr(p, "is_flag", False) else "option")
        opts[p.name] = {"opts": sorted(p.opts), "kind": kind, "required": bool(p.required),
                        "default": None if p.required else _default(p),
                        "multiple": bool(getattr(p, "multiple", False))}
    out = {key: {"options": opts,
                 "extra_args": bool(command.context_settings.get("allow_extra_args"))}}
    if hasattr(command, "commands"):   # a group
        out[key]["commands"] = sorted(command.commands)
        for name in out[key]["commands"]:
            out.update(surface(command.commands[name], path + (name,)))
    return out


def current_surface() -> dict:
    import typer.main

    from skydome.cli import app

    return surface(typer.main.get_command(app))


def test_command_line_surface_matches_the_snapshot():
    want = json.loads(SNAPSHOT.read_text())
    got = current_surface()
    assert sorted(got) == sorted(want), "commands added or lost"
    for key in want:
        assert got[key] == want[key], key


@pytest.mark.parametrize("key", sorted(json.loads(SNAPSHOT.read_text()))
                         if SNAPSHOT.exists() else [])
def test_every_help_lists_its_commands_and_options(key):
    from skydome.cli import app

    want = json.loads(SNAPSHOT.read_text())[key]
    res = CliRunner().invoke(app, key.split()[1:] + ["--help"])
    assert res.exit_code == 0, res.output
    for name in want.get("commands", ()):
        assert f"  {name} " in res.output or f"  {name}\n" in res.output, (key, name)
    for o in want["options"].values():
        for spelling in o["opts"]:
            if spelling.startswith("-"):
                assert spelling in res.output, (key, spelling)


if __name__ == "__main__":  # rewrite the snapshot (only when an option legitimately changes)
    SNAPSHOT.write_text(json.dumps(current_surface(), indent=1, sort_keys=True) + "\n")
