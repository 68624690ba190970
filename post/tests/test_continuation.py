"""Continuation files (periodic orbits followed in one parameter): impactchain.io reads
/continuation, xarray opens it with its dimensions, and the figures and commands `branches`
and `multipliers` draw it.

``write_continuation`` writes the layout the simulator writes: the root and /params of a
version-2 file without the continued parameter, and /continuation with the dimension scales
point (0..P-1), oscillator (1..n), multiplier (1..2n), iterate (1..L) and special (0..S-1)
attached to every dataset, each with ``long_name``, ``units`` and (for the reduced units)
``model_units``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest
from conftest import write_run
from impactchain.io import (SPECIAL_KINDS, Continuation, SchemaError, read_continuation,
                            read_run)

N = 3
"""Oscillators of the synthetic continuation."""

# Branch 0: period 1 from A = 1.0 to 1.6, stable up to its period doubling at point 4;
# branch 1: period 2 from the doubling, A = 1.4 to 1.8, stable up to a Neimark-Sacker point
# at point 10, ending at a grazing at point 11. A fold on branch 0 at point 1 (for the
# legend; synthetic data need not be a real bifurcation diagram).
VALUES = (1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.4, 1.5, 1.6, 1.7, 1.8)
BRANCH = (0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1)
PERIOD = (1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2)
STABLE = (1, 1, 1, 1, 0, 0, 0, 1, 1, 1, 0, 0)
SPECIAL = ((1, "fold"), (4, "period-doubling"), (10, "neimark-sacker"), (11, "grazing"))
END_REASON = "grazing at amplitude = 1.8: the branch ends"


def strobe_positions(values: Sequence[float], period: Sequence[int], n: int) -> np.ndarray:
    """Synthetic positions at the section crossings, (P, L, n), NaN beyond each period."""
    points, longest = len(values), max(period, default=0)
    out = np.full((points, longest, n), np.nan)
    for i, (value, p) in enumerate(zip(values, period)):
        for j in range(p):
            out[i, j] = 0.2 * value * (1 + j) * (-1) ** j - 0.1 * np.arange(n)
    return out


def multipliers(stable: Sequence[int], n: int) -> tuple[np.ndarray, np.ndarray]:
    """Complex pairs of modulus 0.5 .. 0.8 at a stable point, one real 1.5 + i/10 otherwise."""
    points = len(stable)
    re = np.tile(np.linspace(0.5, 0.8, 2 * n), (points, 1))
    im = np.zeros((points, 2 * n))
    im[:, 0::2], im[:, 1::2] = 0.1, -0.1
    for i, s in enumerate(stable):
        if not s:
            re[i, 0], im[i, 0] = 1.5 + i / 10, 0.0
    return re, im


def write_continuation(
    path: str | Path,
    parameter: str = "amplitude",
    values: Sequence[float] = VALUES,
    branch: Sequence[int] = BRANCH,
    period: Sequence[int] = PERIOD,
    stable: Sequence[int] = STABLE,
    special: Sequence[tuple[int, str]] = SPECIAL,
    *,
    fixed_strings: bool = False,
    leave_out: Sequence[str] = (),
) -> Path:
    """Write a synthetic continuation file (n = :data:`N`) and return its path.

    ``special``: (point index, kind) of each special point; ``fixed_strings``: the kinds as
    space-padded fixed-length strings instead of variable-length ones; ``leave_out``:
    datasets of /continuation not to write.
    """
    path = write_run(path, n=N, strobe=False, events=False, schema_version=2)
    n, points = N, len(values)
    with h5py.File(path, "r+") as f:
        del f["final"], f["stats"]
        # /params leaves out the continued parameter, as a sweep's the swept one
        unset = [parameter, "drive_period"] if parameter == "omega" else [parameter]
        for name in unset:
            if name in f["params"].attrs:
                del f["params"].attrs[name]
            elif name in f["params"]:
                del f["params"][name]
        g = f.create_group("continuation")
        g.attrs["parameter"] = parameter
        g.attrs["phase"] = 0.0
        g.attrs["end_reason"] = END_REASON
        strobe_x = strobe_positions(values, period, n)
        x = strobe_x[:, 0, :] if strobe_x.shape[1] else np.zeros((points, n))
        re, im = multipliers(stable, n)
        for name, count, first, long_name in (
                ("point", points, 0, "point index"),
                ("oscillator", n, 1, "oscillator index"),
                ("multiplier", 2 * n, 1, "Floquet multiplier index"),
                ("iterate", strobe_x.shape[1], 1, "section crossing within the period"),
                ("special", len(special), 0, "special point index")):
            g[name] = np.arange(first, first + count, dtype=np.int32)
            g[name].attrs.update(long_name=long_name, units="1")
            g[name].make_scale(name)
        kinds = [kind for _, kind in special]
        kind_data = (np.array([k.encode().ljust(16) for k in kinds], dtype="S16")
                     if fixed_strings else np.array(kinds, dtype=h5py.string_dtype()))
        datasets: dict[str, tuple[Any, str, str, str]] = {
            "values": (np.asarray(values, dtype=float), "point",
                       f"{parameter} (the continued parameter) at the point", "length"),
            "x": (x, "point oscillator",
                  "displacement from equilibrium on the section", "length"),
            "v": (-0.5 * x, "point oscillator", "velocity on the section",
                  "length/time"),
            "strobe_x": (strobe_x, "point iterate oscillator",
                         "displacement at the section crossings of the period", "length"),
            "period": (np.asarray(period, dtype=np.int32), "point",
                       "period of the orbit", "drive cycles"),
            "branch": (np.asarray(branch, dtype=np.int32), "point", "branch index", ""),
            "multipliers_re": (re, "point multiplier", "Floquet multiplier, real part", ""),
            "multipliers_im": (im, "point multiplier", "Floquet multiplier, imaginary part",
                               ""),
            "stable": (np.asarray(stable, dtype=np.int8), "point", "stable orbit", ""),
            "min_gap": (np.where(np.arange(points) == 11, 0.0,
                                 np.linspace(0.5, 0.1, points)), "point",
                        "smallest gap at a local minimum", "length"),
            "min_impact_speed": (np.full(points, math.inf), "point", "smallest impact speed",
                                 "length/time"),
            "impacts_per_period": (np.zeros(points, dtype=np.int32), "point",
                                   "impacts per period", "impacts per period"),
            "residual": (np.full(points, 1e-13), "point", "Newton's last residual", ""),
            "iterations": (np.full(points, 3, dtype=np.int32), "point", "Newton steps", ""),
            "special_index": (np.array([i for i, _ in special], dtype=np.int32), "special",
                              "index of the special point among the points", ""),
            "special_kind": (kind_data, "special", "kind of the special point", ""),
            "special_value": (np.array([values[i] for i, _ in special], dtype=float),
                              "special", f"{parameter} at the special point", "length"),
        }
        for name, (data, dims, long_name, model_units) in datasets.items():
            if name in leave_out:
                continue
            g[name] = data
            g[name].attrs.update(long_name=long_name, units="1")
            if model_units:
                g[name].attrs["model_units"] = model_units
            for axis, dim in enumerate(dims.split()):
                g[name].dims[axis].attach_scale(g[dim])
    return path


@pytest.fixture
def make_continuation(tmp_path: Path) -> Callable[..., Path]:
    """``make_continuation(name, **kw)`` writes ``tmp_path/name`` with
    :func:`write_continuation`."""

    def make(name: str = "cont.h5", **kwargs: Any) -> Path:
        return write_continuation(tmp_path / name, **kwargs)

    return make


@pytest.fixture
def cont_file(make_continuation: Callable[..., Path]) -> Path:
    """The default continuation: two branches, four special points, one of each kind."""
    return make_continuation()


# ---------------------------------------------------------------------------------- reading


def test_reads_every_field(cont_file: Path) -> None:
    run = read_run(cont_file)
    cont = run.continuation
    assert isinstance(cont, Continuation) and run.sweep is None
    assert (cont.parameter, cont.phase, cont.end_reason) == ("amplitude", 0.0, END_REASON)
    assert cont.n_points == len(VALUES)
    np.testing.assert_array_equal(cont.values, VALUES)
    strobe_x = strobe_positions(VALUES, PERIOD, N)
    np.testing.assert_array_equal(cont.strobe_x, strobe_x)
    np.testing.assert_array_equal(cont.x, strobe_x[:, 0, :])
    np.testing.assert_array_equal(cont.v, -0.5 * strobe_x[:, 0, :])
    np.testing.assert_array_equal(cont.period, PERIOD)
    np.testing.assert_array_equal(cont.branch, BRANCH)
    re, im = multipliers(STABLE, N)
    np.testing.assert_array_equal(cont.multipliers_re, re)
    np.testing.assert_array_equal(cont.multipliers_im, im)
    np.testing.assert_array_equal(cont.multipliers, re + 1j * im)
    np.testing.assert_array_equal(cont.max_multiplier, np.abs(re + 1j * im).max(axis=1))
    assert cont.stable.dtype == bool
    np.testing.assert_array_equal(cont.stable, np.array(STABLE) == 1)
    # stable exactly where every multiplier is inside the unit circle (the fixture's design)
    np.testing.assert_array_equal(cont.stable, cont.max_multiplier < 1)
    assert cont.min_gap[-1] == 0.0 and cont.min_gap.shape == (12,)
    assert np.isinf(cont.min_impact_speed).all()
    np.testing.assert_array_equal(cont.impacts_per_period, np.zeros(12))
    np.testing.assert_array_equal(cont.residual, np.full(12, 1e-13))
    np.testing.assert_array_equal(cont.iterations, np.full(12, 3))
    with pytest.raises(ValueError):
        cont.values[0] = 0.0


def test_nan_beyond_each_period(cont_file: Path) -> None:
    cont = read_continuation(cont_file)
    assert cont.strobe_x.shape == (12, max(PERIOD), N)
    for i, p in enumerate(PERIOD):
        assert np.isfinite(cont.strobe_x[i, :p]).all(), i
        assert np.isnan(cont.strobe_x[i, p:]).all(), i


def test_special_points(cont_file: Path) -> None:
    cont = read_continuation(cont_file)
    assert cont.special_points == [(i, kind, VALUES[i]) for i, kind in SPECIAL]
    assert set(cont.special_kind) == set(SPECIAL_KINDS)
    # each located point is itself a point of the continuation
    for index, _, value in cont.special_points:
        assert cont.values[index] == value


@pytest.mark.parametrize("fixed_strings", [False, True])
def test_special_kinds_variable_or_fixed_length(make_continuation: Callable[..., Path],
                                                fixed_strings: bool) -> None:
    cont = read_continuation(make_continuation(fixed_strings=fixed_strings))
    assert list(cont.special_kind) == [kind for _, kind in SPECIAL]


def test_no_special_points(make_continuation: Callable[..., Path]) -> None:
    cont = read_continuation(make_continuation(special=()))
    assert cont.special_points == []
    assert cont.special_index.shape == cont.special_kind.shape == cont.special_value.shape \
        == (0,)


def test_a_continuation_without_points(make_continuation: Callable[..., Path]) -> None:
    """Newton failed at the first point: every per-point dataset has length 0."""
    cont = read_continuation(make_continuation(values=(), branch=(), period=(), stable=(),
                                               special=()))
    assert cont.n_points == 0 and cont.strobe_x.shape == (0, 0, N)
    assert cont.max_multiplier.shape == (0,) and cont.special_points == []


def test_the_continued_parameter_is_not_in_params(make_continuation: Callable[..., Path]
                                                  ) -> None:
    amplitude = read_run(make_continuation("a.h5"))
    assert math.isnan(amplitude.params.amplitude) and amplitude.params.omega == 1.5
    omega = read_run(make_continuation("w.h5", parameter="omega"))
    assert omega.continuation is not None and omega.continuation.parameter == "omega"
    assert math.isnan(omega.params.omega) and math.isnan(omega.params.drive_period)
    assert omega.params.amplitude == 1.7
    spacing = read_run(make_continuation("s.h5", parameter="spacing"))
    assert np.isnan(spacing.params.spacing).all() and spacing.params.spacing.shape == (N + 1,)


def test_units_of_the_file(cont_file: Path) -> None:
    run = read_run(cont_file)
    assert run.unit("continuation/x") == "length"
    assert run.unit("continuation/strobe_x") == "length"
    assert run.unit("continuation/v") == "length/time"
    assert run.unit("continuation/period") == "drive cycles"


def test_required_and_loaded_only_when_asked(cont_file: Path, sweep_file: Path) -> None:
    assert read_run(cont_file, require=("continuation",)).continuation is not None
    assert read_run(cont_file, groups=("initial",)).continuation is None
    with pytest.raises(SchemaError, match=r"no /continuation, needed by branches \(this is "
                                          r"not a continuation file\)"):
        read_run(sweep_file, require=("continuation",), purpose="branches")
    with pytest.raises(SchemaError, match="no /continuation"):
        read_continuation(sweep_file)


@pytest.mark.parametrize("name", ["values", "strobe_x", "stable", "multipliers_im",
                                  "special_kind", "special_value"])
def test_missing_dataset(make_continuation: Callable[..., Path], name: str) -> None:
    path = make_continuation(leave_out=(name,))
    with pytest.raises(SchemaError, match=f"no /continuation/{name} dataset"):
        read_run(path)


def test_missing_attribute(cont_file: Path) -> None:
    with h5py.File(cont_file, "r+") as f:
        del f["continuation"].attrs["end_reason"]
    with pytest.raises(SchemaError, match="/continuation lacks attribute 'end_reason'"):
        read_run(cont_file)


@pytest.mark.parametrize(
    ("name", "data", "message"),
    [
        ("special_kind", np.array(["fold", "cusp", "fold", "grazing"], dtype=h5py.string_dtype()),
         "special_kind holds 'cusp'"),
        ("special_index", np.array([1, 4, 10, 12], dtype=np.int32),
         r"special_index holds values outside 0..11"),
        ("stable", np.full(12, 2, dtype=np.int8), "stable holds values other than 0 and 1"),
        ("period", np.full(12, 3, dtype=np.int32), "2 iterates, fewer than the largest period 3"),
        ("x", np.zeros((N, 12)), r"/continuation/x has shape \(3, 12\), expected \(12, 3\)"),
    ],
)
def test_malformed_data(cont_file: Path, name: str, data: np.ndarray, message: str) -> None:
    with h5py.File(cont_file, "r+") as f:
        del f["continuation"][name]
        f["continuation"][name] = data
    with pytest.raises(SchemaError, match=message):
        read_run(cont_file)


def test_opens_in_xarray_with_its_dimensions(make_continuation: Callable[..., Path]) -> None:
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    for special in (SPECIAL, ()):
        path = make_continuation(f"c{len(special)}.h5", special=special)
        with xr.open_dataset(path, engine="h5netcdf", group="continuation") as ds:
            assert dict(ds.sizes) == {"point": 12, "oscillator": N, "multiplier": 2 * N,
                                      "iterate": 2, "special": len(special)}
            np.testing.assert_array_equal(ds["point"], np.arange(12))
            np.testing.assert_array_equal(ds["oscillator"], [1, 2, 3])
            np.testing.assert_array_equal(ds["multiplier"], np.arange(1, 7))
            np.testing.assert_array_equal(ds["iterate"], [1, 2])
            np.testing.assert_array_equal(ds["special"], np.arange(len(special)))
            assert ds["strobe_x"].dims == ("point", "iterate", "oscillator")
            assert ds["x"].dims == ds["v"].dims == ("point", "oscillator")
            assert ds["multipliers_re"].dims == ("point", "multiplier")
            assert ds["special_kind"].dims == ("special",)
            assert ds.attrs["parameter"] == "amplitude"
            for var in ds.variables.values():
                assert "long_name" in var.attrs and "units" in var.attrs, var.name
            np.testing.assert_array_equal(ds["values"], VALUES)
            strobe_x = ds["strobe_x"].sel(point=7, oscillator=1).values
            np.testing.assert_array_equal(strobe_x, read_continuation(path).strobe_x[7, :, 0])
