"""Every bundled configuration is a preset: ``camdyn presets`` lists each with its kind,
``camdyn presets NAME`` prints its file, and ``camdyn simulate NAME --revolutions 3
--json`` runs every one with the summary keys every kind shares (docs/cli-json.md):
``speed_hz`` [Hz], ``revolutions``, ``impacts_per_revolution`` [1/rev] and
``contact_fraction`` (0 to 1). The expected speed is read from the preset's TOML text and
converted here, not by camdyn. One process: each kind compiles (or loads) once."""

import contextlib
import io
import json
import math
import tomllib
from importlib import resources

import pytest

from camdyn.cli.app import main

FOLDER = resources.files("camdyn.params.presets")
#: What the package ships, by file: every TOML file in the presets folder is a preset.
SHIPPED = sorted(p.name[:-5] for p in FOLDER.iterdir() if p.name.endswith(".toml"))
#: The kinds ``camdyn presets`` may print, and the JSON schema of each kind's run.
SCHEMAS = {"cam-follower": "camdyn.simulate/1", "cam-follower, profile": "camdyn.simulate/1",
           "translating": "camdyn.simulate-translating/1", "rocking": "camdyn.simulate-rocking/1",
           "driven-cam": "camdyn.simulate-mechanism/2", "flexible-pivot": "camdyn.simulate-mechanism/2",
           "two-followers": "camdyn.simulate-mechanism/2"}


def run(*argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def table(name: str) -> dict:
    return tomllib.loads(FOLDER.joinpath(f"{name}.toml").read_text(encoding="utf-8"))


def hertz(text: str) -> float:
    """A speed written with its unit in a preset, in Hz (1 rpm = 1/60 Hz)."""
    value, unit = text.split()
    return {"Hz": 1.0, "rpm": 1.0 / 60.0, "rad/s": 1.0 / (2.0 * math.pi)}[unit] * float(value)


def expected_speed(name: str) -> tuple[float, bool]:
    """The speed [Hz] a preset's file gives, and whether the run holds it (False for a
    shaft under a torque, a motor or a controller, whose speed is the run's)."""
    t = table(name)
    motion = t.get("motion") or t.get("system", {}).get("motion") or {}
    if "speed" not in motion:   # a mechanism on a preset system that keeps its speed
        motion = table(t["mechanism"]["system"])["motion"]
    held = t.get("drive", {}).get("kind", "prescribed") == "prescribed"
    return hertz(motion["speed"]), held


def listed() -> dict:
    status, out, err = run("presets")
    assert status == 0, err
    rows = {}
    for line in out.splitlines():
        cells = [c.strip() for c in line.replace("┃", "│").split("│")]
        if len(cells) > 3 and cells[1] in SHIPPED:
            rows[cells[1]] = cells[2]
    return rows


def test_every_shipped_file_is_listed_with_its_kind():
    rows = listed()
    assert sorted(rows) == SHIPPED and len(SHIPPED) >= 18
    assert set(rows.values()) == set(SCHEMAS)
    for name, kind in rows.items():
        t = table(name)
        declared = t.get("mechanism", {}).get("kind") or t.get("follower", {}).get("kind")
        assert kind == (declared or ("cam-follower, profile" if "profile" in t else "cam-follower")), name
        assert t["preset"]["name"] == name and t["preset"].get("description"), name


def test_every_preset_is_shown_by_name():
    for name in SHIPPED:
        status, out, err = run("presets", name)
        assert status == 0 and out == FOLDER.joinpath(f"{name}.toml").read_text(encoding="utf-8"), (name, err)


@pytest.mark.parametrize("kind", sorted(SCHEMAS))
def test_every_preset_simulates_with_the_common_summary(kind):
    names = [name for name, k in listed().items() if k == kind]
    assert names
    for name in names:
        status, out, err = run("simulate", name, "--revolutions", "3", "--json")
        assert status == 0, (name, err)
        document = json.loads(out)
        assert document["schema"] == SCHEMAS[kind], name
        s = document["summary"]
        speed, held = expected_speed(name)
        if held:
            assert s["speed_hz"] == pytest.approx(speed, rel=1e-12), name
            assert s["revolutions"] == pytest.approx(3.0, rel=1e-3), name
        else:   # a driven shaft: its mean speed lies within the speeds it ran at, and turns it
            low, high = s["speed_min_rad_s"] / (2 * math.pi), s["speed_max_rad_s"] / (2 * math.pi)
            assert low * (1 - 1e-9) <= s["speed_hz"] <= high * (1 + 1e-9), name
            assert s["revolutions"] == pytest.approx(s["speed_hz"] * s["duration_s"], rel=1e-2), name
        assert 0.0 <= s["contact_fraction"] <= 1.0, name
        assert s["impacts_per_revolution"] >= 0.0 and math.isfinite(s["impacts_per_revolution"]), name


@pytest.mark.parametrize("command", [["simulate"], ["presets"], ["spectrum"], ["continue", "--from", "10Hz",
                                                                                 "--to", "11Hz"]])
def test_an_unknown_name_is_refused_with_close_names(command):
    status, out, err = run(command[0], "drum-brak", *command[1:])
    assert status == 2 and err.count("\n") == 1, (out, err)
    assert "'drum-brak'" in err and "drum-brake" in err, err


@pytest.mark.parametrize("name", ["drum-brake", "sundar2014-impact"])
def test_a_sweep_spec_takes_a_preset_by_name_as_its_file(name):
    from camdyn.sweeps.spec import spec_from_dict

    vary = [{"key": "motion.speed" if name.startswith("sundar") else "drive.torque",
             "values": ["10 Hz", "11 Hz"] if name.startswith("sundar") else ["0.1 N*m", "0.2 N*m"]}]
    by_name = spec_from_dict({"system": {"source": name}, "vary": vary})
    by_file = spec_from_dict({"system": {"source": str(FOLDER.joinpath(f"{name}.toml"))}, "vary": vary})
    assert by_name.system_toml == by_file.system_toml and by_name.points == 2


def test_the_parameter_sets_page_lists_every_preset():
    from pathlib import Path

    from camdyn.params import catalog

    page = (Path(__file__).resolve().parents[1] / "docs" / "presets.md").read_text(encoding="utf-8")
    missing = [name for name in catalog.preset_names() if f"| `{name}` |" not in page]
    assert missing == [], f"docs/presets.md has no row for {missing}"
