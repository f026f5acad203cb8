"""Fuzzing the readers of user input: whatever the bytes, the outcome is a camdyn error
(a CamdynError with a one-line message) or a valid result, never another exception.

Covered: the record readers fed random bytes under every suffix, truncated and mutated
valid records (CSV, netCDF, UFF), the TOML configuration reader, the ``--set`` parser, and
the command line on bad records and bad assignments. The examples are derandomized, so
every run tries the same inputs.
"""

import contextlib
import io
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from camdyn.cli.app import main
from camdyn.errors import CamdynError
from camdyn.io.measurements import RECORD_SUFFIXES, make_record, read_measurement, write_measurement
from camdyn.params.config import SCHEMA, load_system, parse_assignments, preset_text

FUZZ = dict(deadline=None, derandomize=True, database=None,
            suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture,
                                   HealthCheck.data_too_large])

PRESET = "sundar2014-impact"
FORMATS = (".csv", ".nc", ".uff")
SUFFIXES = sorted(RECORD_SUFFIXES) + [".dat", ""]

#: Starts of files that lead the readers past their first checks.
PREFIXES = [b"", b"\x89HDF\r\n\x1a\n", b"CDF\x01", b"CDF\x02", b"    -1\n    58\n", b"\xef\xbb\xbf",
            b"\xff\xfe", b"# speed = 11.55 Hz\n", b"time,Nx,Ny,alpha_ddot\n", b"time;Nx\n0;1\n",
            b"# units: time ms\ntime,Nx\n", b"PK\x03\x04"]

#: Values near a valid one: wrong or missing units, non-finite numbers, wrong types.
NEAR_VALUES = ["nan", "inf", "-inf", "1e400", "-1", "0", "1e-300", "3.5", "3.5 mmm", "3.5 m/s", "3,5 mm",
               "3.5 mm mm", "1/0 mm", "fast", "", "16 Hz", "960 rpm", "1 kg", "24.7 GN*s/m^2.5", "true", "µm",
               "1 degC", "1 %", "2 ** 1000 m", "(1", "3.5mm", "-0 mm", "0x10 mm"]
NEAR_TOML = ["nan", "inf", "-inf", "1e400", "-1", "0", "3.5", "true", "[1, 2]", "{ a = 1 }", '"3.5 mmm"',
             '"3.5 m/s"', '"fast"', '""', '"nan mm"', '"inf Hz"', "1979-05-27", '"1 kg"', '"3,5 mm"']


@pytest.fixture(scope="module")
def valid_files(tmp_path_factory):
    """The bytes of a small valid record as CSV, netCDF and UFF."""
    folder = tmp_path_factory.mktemp("valid")
    time = np.arange(64) / 10e3
    record = make_record(time, {"Nx": np.sin(70 * time), "Ny": -8 + np.cos(70 * time),
                                "alpha_ddot": 300 * np.sin(72 * time)}, speed_hz=11.55, runout=5.25e-3)
    return {suffix: write_measurement(record, folder / f"record{suffix}").read_bytes() for suffix in FORMATS}


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("fuzz")


def assert_one_line(exc: BaseException) -> None:
    message = str(exc)
    assert message.strip() and "\n" not in message and "Traceback" not in message, repr(message)


def read_outcome(path):
    """Read ``path``: a camdyn error with a one-line message, or a valid record."""
    try:
        record = read_measurement(path)
    except CamdynError as exc:
        assert_one_line(exc)
        return None
    time = record["time"].values
    assert time.size >= 16 and np.all(np.diff(time) > 0)
    assert record.data_vars and all(record[name].shape == time.shape for name in record.data_vars)
    assert record.attrs["sample_rate"] > 0
    return record


@st.composite
def mutations(draw, original: bytes) -> bytes:
    """``original`` with a few bytes flipped, replaced by punctuation, inserted or deleted."""
    data = bytearray(original)
    for _ in range(draw(st.integers(1, 6))):
        position = draw(st.integers(0, max(len(data) - 1, 0)))
        action = draw(st.sampled_from(("flip", "punctuate", "insert", "delete")))
        if action == "flip" and data:
            data[position] ^= 1 << draw(st.integers(0, 7))
        elif action == "punctuate" and data:
            data[position] = draw(st.sampled_from(b",;\t\n\r -.e9#=\"[]\x00\xff"))
        elif action == "insert":
            data[position:position] = draw(st.binary(min_size=1, max_size=8))
        else:
            del data[position:position + draw(st.integers(1, 64))]
    return bytes(data)


@settings(max_examples=150, **FUZZ)
@given(prefix=st.sampled_from(PREFIXES), body=st.binary(max_size=600), suffix=st.sampled_from(SUFFIXES))
def test_random_bytes_under_every_suffix(folder, prefix, body, suffix):
    path = folder / f"random{suffix}"
    path.write_bytes(prefix + body)
    read_outcome(path)


@settings(max_examples=100, **FUZZ)
@given(suffix=st.sampled_from(FORMATS), fraction=st.floats(0.0, 1.0))
def test_truncated_records(folder, valid_files, suffix, fraction):
    original = valid_files[suffix]
    path = folder / f"truncated{suffix}"
    path.write_bytes(original[:int(fraction * len(original))])
    read_outcome(path)


@settings(max_examples=150, **FUZZ)
@given(suffix=st.sampled_from(FORMATS), data=st.data())
def test_mutated_records(folder, valid_files, suffix, data):
    path = folder / f"mutated{suffix}"
    path.write_bytes(data.draw(mutations(valid_files[suffix])))
    read_outcome(path)


def config_outcome(action) -> None:
    """Run ``action``: a system, or a camdyn error with a one-line message."""
    try:
        action()
    except CamdynError as exc:
        assert_one_line(exc)


@st.composite
def near_miss_toml(draw) -> bytes:
    """The preset's TOML with a value or key replaced by a near miss, then byte mutations."""
    lines = preset_text(PRESET).splitlines()
    assignments = [i for i, line in enumerate(lines) if re.match(r"^\w+ = ", line)]
    for _ in range(draw(st.integers(0, 3))):
        i = draw(st.sampled_from(assignments))
        key, value = lines[i].split(" = ", 1)
        if draw(st.booleans()):
            lines[i] = f"{key} = {draw(st.sampled_from(NEAR_TOML))}"
        else:
            lines[i] = f"{draw(st.sampled_from(['direction', key + 's', key.upper(), key[:-1]]))} = {value}"
    text = "\n".join(lines).encode()
    return draw(mutations(text)) if draw(st.booleans()) else text


@settings(max_examples=150, **FUZZ)
@given(raw=st.one_of(st.text(max_size=300).map(str.encode), near_miss_toml()))
def test_configuration_files(folder, raw):
    path = folder / "config.toml"
    path.write_bytes(raw)
    config_outcome(lambda: load_system(path))


keys = st.one_of(st.sampled_from(sorted(SCHEMA)),
                 st.sampled_from(sorted(SCHEMA)).map(lambda k: k.replace(".", "_")),
                 st.sampled_from(sorted(SCHEMA)).map(lambda k: k[:-1]),
                 st.sampled_from(sorted(SCHEMA)).map(str.upper),
                 st.text(max_size=12))
values = st.one_of(st.sampled_from(NEAR_VALUES), st.text(max_size=12))
assignments = st.lists(st.one_of(st.builds(lambda k, v: f"{k}={v}", keys, values), st.text(max_size=20)),
                       max_size=3)


@settings(max_examples=150, **FUZZ)
@given(items=assignments)
def test_set_assignments(items):
    def action():
        load_system(PRESET, parse_assignments(items))

    config_outcome(action)


def cli_outcome(argv) -> None:
    """The command line refuses with exit status 2 and one line ``error: ...``."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    lines = [line for line in (out.getvalue() + err.getvalue()).splitlines() if line.strip()]
    assert status == 2, (status, lines)
    assert len(lines) == 1 and lines[0].startswith("error:") and "unexpected" not in lines[0], lines


COMMANDS = [["identify", "friction", PRESET], ["identify", "modal-damping"],
            ["identify", "impact-damping", PRESET], ["identify", "restitution", PRESET]]


@settings(max_examples=60, **FUZZ)
@given(command=st.sampled_from(COMMANDS), prefix=st.sampled_from(PREFIXES), body=st.binary(max_size=300),
       suffix=st.sampled_from(SUFFIXES))
def test_cli_refuses_random_files(folder, command, prefix, body, suffix):
    path = folder / f"cli{suffix}"
    path.write_bytes(prefix + body)
    cli_outcome([*command, path])


@settings(max_examples=60, **FUZZ)
@given(command=st.sampled_from([c for c in COMMANDS if c[-1] == PRESET]), suffix=st.sampled_from(FORMATS),
       fraction=st.floats(0.0, 0.2))
def test_cli_refuses_truncated_records(folder, valid_files, command, suffix, fraction):
    path = folder / f"cli_truncated{suffix}"
    original = valid_files[suffix]
    path.write_bytes(original[:int(fraction * len(original))])
    cli_outcome([*command, path])


@settings(max_examples=60, **FUZZ)
@given(items=assignments)
def test_cli_refuses_bad_assignments(folder, items):
    argv = ["identify", "restitution", PRESET, folder / "missing.csv"]
    for item in items:
        argv += ["--set", item]
    cli_outcome(argv)


def test_non_utf8_configuration_is_refused(tmp_path):
    path = tmp_path / "latin.toml"
    path.write_bytes(preset_text(PRESET).encode() + b"\n# caf\xe9\n")
    with pytest.raises(CamdynError, match="not UTF-8"):
        load_system(path)


def test_non_finite_exponent_is_refused():
    with pytest.raises(CamdynError, match="finite"):
        load_system(PRESET, parse_assignments(["contact.exponent=nan"]))


def test_infinite_direction_is_refused(tmp_path):
    path = tmp_path / "direction.toml"
    path.write_text(preset_text(PRESET).replace("[motion]", "[motion]\ndirection = inf"))
    with pytest.raises(CamdynError, match="whole number"):
        load_system(path)


def test_decimal_comma_and_numbers_side_by_side_are_refused():
    for text in ("3,5 mm", "3 4 mm"):
        with pytest.raises(CamdynError, match="comma|two numbers"):
            load_system(PRESET, parse_assignments([f"cam.runout={text}"]))


@settings(max_examples=100, **FUZZ)
@given(raw=st.one_of(st.binary(max_size=300), st.text(max_size=300).map(str.encode)))
def test_sweep_spec_files(folder, raw):
    from camdyn.sweeps import load_spec

    path = folder / "spec.toml"
    path.write_bytes(raw)
    config_outcome(lambda: load_spec(path))
