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
