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


def test_every_sun_option_states_the_one_declared_range():
    """The sun options are declared once: wherever a command has --sun-elevation,
    --sun-azimuth, --lat or --lon, its help states the declared range (aureole's narrower
    lower end of the elevation, 1 deg, excepted), and the ranges are those that
    skydome.sun.sun_from_options checks."""
    import typer.main

    from skydome.cli import app

    ranges = {"sun_elevation": "..90", "sun_azimuth": "-360..360", "lat": "-90..90",
              "lon": "-180..180"}
    seen = set()

    def walk(cmd, path):
        if hasattr(cmd, "commands"):
            for name, sub in cmd.commands.items():
                walk(sub, path + (name,))
            return
        for p in cmd.params:
            if p.name in ranges or (p.name == "method" and path == ("sun",)):
                seen.add((path, p.name))
                text = p.help or ""
                if p.name in ranges:
                    assert ranges[p.name] in text, (path, p.name, text)
                    if p.name == "sun_elevation" and path != ("aureole",):
                        assert "-90..90" in text, (path, text)
    walk(typer.main.get_command(app), ())
    commands = {path for path, _ in seen}
    assert len(commands) >= 12, sorted(commands)


def test_the_declared_sun_ranges_are_those_the_library_checks():
    """The command line's declaration of the sun options and skydome.sun.sun_from_options
    (which every command's sun goes through) accept and refuse the same values: each range's
    ends pass, a step beyond either end is refused naming the option."""
    from skydome.cli._kit import SUN_OPTIONS
    from skydome.sun import sun_from_options

    place = {"lat": 48.2, "lon": 16.4, "time": "2026-06-21T12:00+02:00"}
    for name, (_, _, rng, _) in SUN_OPTIONS.items():
        if rng is None:
            continue
        for value, ok in ((rng[0], True), (rng[1], True), (rng[0] - 1e-6, False),
                          (rng[1] + 1e-6, False)):
            kw = dict(place, **{name: value}) if name in place else {name: value}
            if ok:
                sun_from_options(**kw)
            else:
                with pytest.raises(ValueError, match=name):
                    sun_from_options(**kw)
