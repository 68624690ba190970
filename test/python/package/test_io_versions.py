"""impactchain.io reads the simulator's files of schema versions 1 and 2 (test/python/package/data: the same
two inputs written by both) into the same numbers; version 2 also opens group by group in
xarray with named dimensions and coordinates."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import h5py
import numpy as np
import pytest

from impactchain.io import READABLE_VERSIONS, SCHEMA_VERSION, read_run

DATA = Path(__file__).resolve().parent / "data"
PARTS = ("initial", "final", "strobe", "events", "stats", "lyapunov")


def _same(a: object, b: object) -> bool:
    """Equal values (arrays bit for bit, NaN equal to NaN)."""
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        a, b = np.asarray(a), np.asarray(b)
        return a.shape == b.shape and bool(np.array_equal(
            a, b, equal_nan=a.dtype.kind == "f" and b.dtype.kind == "f"))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def _differences(a: object, b: object) -> list[str]:
    return [field.name for field in dataclasses.fields(a)
            if not _same(getattr(a, field.name), getattr(b, field.name))]


def test_versions() -> None:
    assert SCHEMA_VERSION == 2 and READABLE_VERSIONS == (1, 2)
    for name, version in (("v1_run.h5", 1), ("v2_run.h5", 2)):
        assert read_run(DATA / name).schema_version == version


def test_a_run_reads_the_same_from_both_versions() -> None:
    v1, v2 = read_run(DATA / "v1_run.h5"), read_run(DATA / "v2_run.h5")
    assert not _differences(v1.params, v2.params)
    for part in PARTS:
        assert getattr(v1, part) is not None, part
        assert not _differences(getattr(v1, part), getattr(v2, part)), part
    # the reduced units of version 1's `units` are version 2's `model_units`
    for name in ("strobe/x", "strobe/v", "events/time", "lyapunov/exponents", "initial/x"):
        assert v1.unit(name) == v2.unit(name), name
    with h5py.File(DATA / "v2_run.h5") as f:
        assert f["strobe/x"].attrs["units"] == "1"
        assert f["strobe/x"].attrs["model_units"] == "length"
        assert f["lyapunov/exponents"].attrs["units"] == "bit"
        assert f["final/phase"].shape == () and f["final/phase"].attrs["units"] == "radian"


def test_a_2d_sweep_reads_the_same_from_both_versions() -> None:
    v1, v2 = read_run(DATA / "v1_sweep2d.h5"), read_run(DATA / "v2_sweep2d.h5")
    assert v1.sweep is not None and v2.sweep is not None
    assert _differences(v1.sweep, v2.sweep) == ["drive_period"]
    assert v1.sweep.drive_period is None
    np.testing.assert_allclose(v2.sweep.drive_period, 2 * np.pi / v2.sweep.values[:, 1],
                               rtol=1e-15)
    assert v1.sweep.values.shape == (6, 2) and v1.sweep.x.shape == (6, 4, 2)
    # version 1 stores the swept parameters' first values at the top; version 2 leaves them
    # out, and drive_period with omega
    assert v1.params.amplitude == 1.7 and v1.params.omega == 1.5
    assert math.isnan(v2.params.amplitude) and math.isnan(v2.params.omega)
    assert math.isnan(v2.params.drive_period)
    assert not _differences(dataclasses.replace(v1.params, amplitude=math.nan,
                                                omega=math.nan, drive_period=math.nan),
                            v2.params)
    with h5py.File(DATA / "v2_sweep2d.h5") as f:
        params = f["params"].attrs
        assert not {"amplitude", "omega", "drive_period"} & set(params)
        # (point, point2, record, oscillator): the points in version 1 are p = i + 3 j
        x = f["sweep/x"][()]
        assert x.shape == (3, 2, 4, 2)
        np.testing.assert_array_equal(x[2, 1], v1.sweep.x[2 + 3 * 1])


@pytest.mark.parametrize("name", ["v2_run.h5", "v2_sweep2d.h5"])
def test_version_2_opens_in_xarray_group_by_group(name: str) -> None:
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    with h5py.File(DATA / name) as f:
        groups = list(f)
    for group in groups:
        with xr.open_dataset(DATA / name, engine="h5netcdf", group=group) as ds:
            assert not [d for d in ds.dims if str(d).startswith("phony_dim")], group
            for var in ds.variables.values():
                assert "long_name" in var.attrs and "units" in var.attrs, (group, var.name)
