"""Measurement readers: CSV, netCDF and UFF 58 round trips, and refusals of bad records."""

import numpy as np
import pytest

from camdyn.errors import DataError
from camdyn.io.measurements import (
    angular_acceleration,
    check_record,
    make_record,
    read_measurement,
    write_measurement,
)


@pytest.fixture()
def record():
    t = np.arange(2000) / 10e3
    return make_record(t, {"Nx": np.sin(70 * t), "Ny": -8 + np.cos(70 * t), "alpha_ddot": 300 * np.sin(72 * t)},
                       speed_hz=11.55, runout=5.25e-3)


@pytest.mark.parametrize("suffix", [".csv", ".nc", ".uff"])
def test_round_trip(tmp_path, record, suffix):
    path = write_measurement(record, tmp_path / f"rec{suffix}")
    back = read_measurement(path)
    for name in ("Nx", "Ny", "alpha_ddot"):
        np.testing.assert_allclose(back[name].values, record[name].values, rtol=1e-8, atol=1e-8)
    assert back.attrs["speed_hz"] == pytest.approx(11.55)
    assert back.attrs["runout"] == pytest.approx(5.25e-3)
    assert back.attrs["sample_rate"] == pytest.approx(10e3)


def test_netcdf_units_are_converted(tmp_path, record):
    ds = record.copy()
    ds["Nx"] = ds["Nx"] * 1000
    ds["Nx"].attrs["units"] = "mN"
    ds[["Nx", "Ny", "alpha_ddot"]].to_netcdf(tmp_path / "r.nc", engine="h5netcdf")
    np.testing.assert_allclose(read_measurement(tmp_path / "r.nc")["Nx"].values, record["Nx"].values, rtol=1e-12)


def test_netcdf_without_units_refused(tmp_path, record):
    ds = record.copy()
    del ds["Ny"].attrs["units"]
    ds.to_netcdf(tmp_path / "r.nc", engine="h5netcdf")
    with pytest.raises(DataError, match="no units"):
        read_measurement(tmp_path / "r.nc")


def test_gap_refused():
    t = np.arange(100) / 1e3
    t[50:] += 0.01
    with pytest.raises(DataError, match="gap of 0.011 s at t = 0.049"):
        make_record(t, {"Nx": np.zeros(100) + 1.0})


def test_nan_and_clipping_refused(record):
    bad = record.copy(deep=True)
    bad["Nx"].values[10] = np.nan
    with pytest.raises(DataError, match="1 NaN"):
        check_record(bad)
    clipped = record.copy(deep=True)
    clipped["alpha_ddot"].values[:] = np.clip(clipped["alpha_ddot"].values, -250, 250)
    with pytest.raises(DataError, match="clipped at its upper limit 250"):
        check_record(clipped)


def test_csv_errors(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("time,Nx,Fz\n0,1,2\n")
    with pytest.raises(DataError, match="unknown columns"):
        read_measurement(p)
    with pytest.raises(DataError, match="no such file"):
        read_measurement(tmp_path / "missing.csv")
    q = tmp_path / "b.xlsx"
    q.write_text("x")
    with pytest.raises(DataError, match="unknown measurement format"):
        read_measurement(q)


def test_tangential_acceleration(record):
    ds = make_record(record["time"].values, {"a_t": 0.063 * record["alpha_ddot"].values})
    out = angular_acceleration(ds, 0.063)
    np.testing.assert_allclose(out["alpha_ddot"].values, record["alpha_ddot"].values, rtol=1e-12)
    with pytest.raises(DataError, match="accelerometer distance"):
        angular_acceleration(ds, None)


# Readers that say what is wrong: one test per kind of unusable (or tolerated) file.

def _csv_text(record, time_unit="s", delimiter=","):
    """A CSV record by hand: header and rows, time in ``time_unit``."""
    scale = {"s": 1.0, "ms": 1e3}[time_unit]
    rows = [delimiter.join(f"{v:.10g}" for v in (t * scale, nx)) for t, nx in
            zip(record["time"].values, record["Nx"].values)]
    return "\n".join(rows) + "\n"


def test_utf8_byte_order_mark_accepted(tmp_path, record):
    path = write_measurement(record, tmp_path / "rec.csv")
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    back = read_measurement(path)
    np.testing.assert_allclose(back["Nx"].values, record["Nx"].values, rtol=1e-8, atol=1e-8)
    assert back.attrs["speed_hz"] == pytest.approx(11.55)


def test_semicolon_and_tab_delimiters_accepted(tmp_path, record):
    semicolon = tmp_path / "semicolon.csv"
    semicolon.write_text("# speed = 11.55 Hz\ntime;Nx\n" + _csv_text(record, delimiter=";").replace(".", ","))
    back = read_measurement(semicolon)    # a decimal comma too, as German Excel writes it
    np.testing.assert_allclose(back["Nx"].values, record["Nx"].values, rtol=1e-8, atol=1e-8)
    tab = tmp_path / "tab.csv"
    tab.write_text("time\tNx\n" + _csv_text(record, delimiter="\t"))
    np.testing.assert_allclose(read_measurement(tab)["Nx"].values, record["Nx"].values, rtol=1e-8, atol=1e-8)
    comma = tmp_path / "comma.csv"
    comma.write_text("# speed = 11,55 Hz\ntime;Nx\n" + _csv_text(record, delimiter=";"))
    with pytest.raises(DataError, match=r"line 1: the metadata entry speed = '11,55 Hz' has a comma"):
        read_measurement(comma)


def test_time_in_milliseconds(tmp_path, record):
    rows = _csv_text(record, time_unit="ms")
    for header in ("time [ms],Nx\n", "time_ms,Nx\n", "# units: time ms\ntime,Nx\n"):
        path = tmp_path / "ms.csv"
        path.write_text(header + rows)
        assert read_measurement(path).attrs["sample_rate"] == pytest.approx(10e3), header
    path.write_text("# speed = 11.55 Hz\ntime,Nx\n" + rows)
    with pytest.raises(DataError, match=r"steps by 0\.1 per sample and states no unit.*0\.866 samples per cam "
                                        r"revolution at the stated 11\.55 Hz.*looks like milliseconds.*time \[ms\]"):
        read_measurement(path)


def test_header_only_csv(tmp_path):
    path = tmp_path / "header.csv"
    path.write_text("# speed = 16 Hz\ntime,Nx,Ny,alpha_ddot\n")
    with pytest.raises(DataError, match=r"header\.csv: the header row \(line 2\) is followed by no samples"):
        read_measurement(path)


def test_binary_data_named_csv(tmp_path):
    path = tmp_path / "noise.csv"
    path.write_bytes(bytes(np.random.default_rng(1).integers(0, 256, 2000, dtype=np.uint8)))
    with pytest.raises(DataError, match=r"noise\.csv: binary file, not CSV text$"):
        read_measurement(path)


def test_plain_hdf5_named(tmp_path, record):
    h5py = pytest.importorskip("h5py")
    path = tmp_path / "plain.h5"
    with h5py.File(path, "w") as handle:
        handle["time"] = record["time"].values
        handle["Nx"] = record["Nx"].values
        handle["Nx"].attrs["units"] = "N"
    with pytest.raises(DataError, match=r"plain\.h5: an HDF5 file without netCDF dimensions/time coordinate "
                                        r".*write it with xarray, Dataset\.to_netcdf\(path, engine='h5netcdf'\)"):
        read_measurement(path)


def test_truncated_uff(tmp_path, record):
    path = write_measurement(record, tmp_path / "rec.uff")
    data = path.read_bytes()
    path.write_bytes(data[:len(data) // 2])
    with pytest.raises(DataError, match=r"rec\.uff: a truncated UFF file: the dataset that starts on line \d+ "
                                        r"has no closing '    -1' line"):
        read_measurement(path)


def test_netcdf_bytes_named_csv(tmp_path, record):
    source = write_measurement(record, tmp_path / "rec.nc")
    path = tmp_path / "rec.csv"
    path.write_bytes(source.read_bytes())
    with pytest.raises(DataError, match=r"rec\.csv: binary file, not CSV text: it looks like a netCDF-4/HDF5 "
                                        r"file; rename it to \.nc"):
        read_measurement(path)


@pytest.mark.parametrize("suffix", [".csv", ".nc", ".uff"])
def test_empty_file(tmp_path, suffix):
    path = tmp_path / f"empty{suffix}"
    path.write_bytes(b"")
    with pytest.raises(DataError, match=r"the file is empty \(0 bytes\)"):
        read_measurement(path)


def test_non_utf8_text(tmp_path, record):
    rows = _csv_text(record).encode()
    latin_comment = tmp_path / "comment.csv"
    latin_comment.write_bytes(b"# preset = caf\xe9 rig\n# speed = 11.55 Hz\ntime,Nx\n" + rows)
    back = read_measurement(latin_comment)    # Latin-1 comments are harmless: read as Windows-1252
    assert back.attrs["preset"] == "café rig" and back.attrs["speed_hz"] == pytest.approx(11.55)
    latin_header = tmp_path / "header.csv"
    latin_header.write_bytes(b"time,Nx\n" + rows[:30] + b"\xb5\n" + rows[30:])
    with pytest.raises(DataError, match=r"header\.csv: line \d+ is not UTF-8 text \(byte 0xb5 at column \d+.*"
                                        r"save the file as UTF-8"):
        read_measurement(latin_header)


def test_wrong_suffix_and_unknown_suffix_say_what_the_file_looks_like(tmp_path, record):
    text = write_measurement(record, tmp_path / "rec.csv").read_bytes()
    named_uff = tmp_path / "rec.uff"
    named_uff.write_bytes(text)
    with pytest.raises(DataError, match=r"not a UFF file: it looks like text \(CSV or similar\); if it is a CSV "
                                        r"record, rename it to \.csv"):
        read_measurement(named_uff)
    named_dat = tmp_path / "rec.dat"
    named_dat.write_bytes(write_measurement(record, tmp_path / "r.uff").read_bytes())
    with pytest.raises(DataError, match=r"unknown measurement format '\.dat'.*looks like a UFF"):
        read_measurement(named_dat)


def test_sampling_refusals_name_the_file(tmp_path, record):
    path = write_measurement(record, tmp_path / "gap.csv")
    lines = path.read_text().splitlines()
    del lines[100:110]                                   # ten samples lost: a gap
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(DataError, match=r"gap\.csv: sampling is not uniform: a gap of 0\.0011 s"):
        read_measurement(path)
    spoiled = record.copy(deep=True)
    spoiled["Nx"].values[101] = np.nan
    nan = write_measurement(spoiled, tmp_path / "nan.csv")
    with pytest.raises(DataError, match="channel Nx holds 1 NaN"):
        check_record(read_measurement(nan))
    extra = write_measurement(record, tmp_path / "extra.csv")
    extra.write_text(extra.read_text().replace("\n0.0101,", "\n0.0101,0.5,", 1))
    with pytest.raises(DataError, match=r"extra\.csv: line 106 has 5 values but the header names 4 columns"):
        read_measurement(extra)


def test_missing_header_row_named(tmp_path, record):
    path = tmp_path / "bare.csv"
    path.write_text(_csv_text(record))
    with pytest.raises(DataError, match=r"bare\.csv: line 1 holds numbers where the header row"):
        read_measurement(path)


@pytest.mark.parametrize("codec", ["utf-16", "utf-16-le"])
def test_utf16_text_accepted(tmp_path, record, codec):
    path = tmp_path / "unicode.csv"                      # Excel's "Unicode text": UTF-16, tabs
    path.write_bytes(("time\tNx\n" + _csv_text(record, delimiter="\t")).encode(codec))
    np.testing.assert_allclose(read_measurement(path)["Nx"].values, record["Nx"].values, rtol=1e-8, atol=1e-8)
