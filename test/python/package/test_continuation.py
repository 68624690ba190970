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
import re
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.collections import PathCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from conftest import write_run
from impactchain import figures, schema
from impactchain.cli import main
from impactchain.io import (SPECIAL_KINDS, Continuation, SchemaError, read_continuation,
                            read_run)

MakeRun = Callable[..., Path]

N = 3
"""Oscillators of the synthetic continuation."""

# Branch 0: period 1 from A = 1.0 to 1.6, stable up to its period doubling at point 4;
# branch 1: period 2 from the doubling, A = 1.4 to 1.8, stable up to a Neimark-Sacker point
# at point 10, ending at a grazing at point 11. A fold on branch 0 at point 1, a corner at
# point 2, an impact at the section at point 5 and a branch point on branch 1 at point 8 (for
# the legend; synthetic data need not be a real bifurcation diagram).
VALUES = (1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.4, 1.5, 1.6, 1.7, 1.8)
BRANCH = (0, 0, 0, 0, 0, 0, 0, 1, 1, 1, 1, 1)
PERIOD = (1, 1, 1, 1, 1, 1, 1, 2, 2, 2, 2, 2)
STABLE = (1, 1, 1, 1, 0, 0, 0, 1, 1, 1, 0, 0)
SPECIAL = ((1, "fold"), (2, "corner"), (4, "period-doubling"), (5, "section"),
           (8, "branch-point"), (10, "neimark-sacker"), (11, "grazing"))
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
        for name, count, first in (("point", points, 0), ("oscillator", n, 1),
                                   ("multiplier", 2 * n, 1),
                                   ("iterate", strobe_x.shape[1], 1),
                                   ("special", len(special), 0)):
            g[name] = np.arange(first, first + count, dtype=np.int32)
            g[name].attrs.update(schema.attributes(schema.output(f"/continuation/{name}")))
            g[name].make_scale(name)
        kinds = [kind for _, kind in special]
        kind_data = (np.array([k.encode().ljust(16) for k in kinds], dtype="S16")
                     if fixed_strings else np.array(kinds, dtype=h5py.string_dtype()))
        # the description of each dataset is the file schema's (impactchain.schema)
        datasets: dict[str, Any] = {
            "values": np.asarray(values, dtype=float),
            "x": x,
            "v": -0.5 * x,
            "strobe_x": strobe_x,
            "period": np.asarray(period, dtype=np.int32),
            "branch": np.asarray(branch, dtype=np.int32),
            "multipliers_re": re,
            "multipliers_im": im,
            "stable": np.asarray(stable, dtype=np.int8),
            "min_gap": np.where(np.arange(points) == 11, 0.0, np.linspace(0.5, 0.1, points)),
            "min_impact_speed": np.full(points, math.inf),
            "impacts_per_period": np.zeros(points, dtype=np.int32),
            "residual": np.full(points, 1e-13),
            "iterations": np.full(points, 3, dtype=np.int32),
            "special_index": np.array([i for i, _ in special], dtype=np.int32),
            "special_kind": kind_data,
            "special_value": np.array([values[i] for i, _ in special], dtype=float),
        }
        for name, data in datasets.items():
            if name in leave_out:
                continue
            entry = schema.output(f"/continuation/{name}")
            g[name] = data
            g[name].attrs.update(schema.attributes(entry, parameter))
            for axis, dim in enumerate(schema.dims(entry)):
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
        ("special_kind", np.array(["fold", "cusp", "fold", "grazing", "corner", "section",
                                   "branch-point"], dtype=h5py.string_dtype()),
         "special_kind holds 'cusp'"),
        ("special_index", np.array([1, 2, 4, 5, 8, 10, 12], dtype=np.int32),
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


# ---------------------------------------------------------------------------------- figures


RUNS = {"branch-0-stable": range(0, 4), "branch-0-unstable": range(3, 7),
        "branch-1-stable": range(7, 10), "branch-1-unstable": range(9, 12)}
"""The points of each line of the default continuation, by the lines' gid."""


def _lines(ax: Axes, prefix: str) -> list[Line2D]:
    return [line for line in ax.get_lines() if (line.get_gid() or "").startswith(prefix)]


def _markers(ax: Axes) -> dict[str, np.ndarray]:
    """The special-point markers of each kind: their (x, y)."""
    return {str(c.get_gid())[len("special-"):]: np.asarray(c.get_offsets())
            for c in ax.collections
            if isinstance(c, PathCollection) and (c.get_gid() or "").startswith("special-")}


def _legend(ax: Axes) -> list[str]:
    legend = ax.get_legend()
    assert legend is not None
    return [text.get_text() for text in legend.get_texts()]


@pytest.fixture
def comparable_sweep(make_run: MakeRun) -> Path:
    """A sweep of the continuation's parameter on its chain (n = 3, the same parameters)."""
    return make_run("sweep.h5", n=N, strobe=False, events=False, sweep=True)


def test_branches_are_the_section_crossings(cont_file: Path) -> None:
    """A line per crossing of each run of equal stability on a branch: solid while stable,
    dashed while unstable, a run after a change of stability starting at the last point of
    the run before it, a new line at a new branch."""
    cont = read_continuation(cont_file)
    site = 2
    fig = figures.branches(cont_file, site=site)
    assert isinstance(fig, Figure)
    (ax,) = fig.axes
    lines = _lines(ax, "branch-")
    assert sorted({str(line.get_gid()) for line in lines}) == sorted(RUNS)
    for gid, points in RUNS.items():
        drawn = [line for line in lines if line.get_gid() == gid]
        assert len(drawn) == PERIOD[points[-1]], gid  # one line per crossing
        for j, line in enumerate(drawn):
            np.testing.assert_array_equal(line.get_xdata(), cont.values[list(points)])
            np.testing.assert_array_equal(line.get_ydata(),
                                          cont.strobe_x[list(points), j, site - 1])
            assert line.get_linestyle() == ("-" if gid.endswith("-stable") else "--"), gid
    assert len({line.get_color() for line in lines if "branch-0" in str(line.get_gid())}) == 1
    assert _lines(ax, "branch-0")[0].get_color() != _lines(ax, "branch-1")[0].get_color()


def test_branches_mark_the_special_points_at_every_crossing(cont_file: Path) -> None:
    cont = read_continuation(cont_file)
    ax = figures.branches(cont_file).axes[0]
    markers = _markers(ax)
    assert sorted(markers) == sorted(SPECIAL_KINDS)
    # one marker per crossing of the special orbit: 1 + 1 + 1 + 1 (period 1), 2 + 2 + 2
    # (period 2)
    assert sum(len(xy) for xy in markers.values()) == sum(PERIOD[i] for i, _ in SPECIAL) == 10
    for index, kind in SPECIAL:
        p = PERIOD[index]
        np.testing.assert_array_equal(markers[kind][:, 0], np.full(p, VALUES[index]))
        np.testing.assert_array_equal(markers[kind][:, 1], cont.strobe_x[index, :p, 0])
    assert len({tuple(c.get_paths()[0].vertices.ravel()) for c in ax.collections}) == 7
    assert _legend(ax) == ["stable", "unstable", "fold", "period doubling", "Neimark-Sacker",
                           "grazing", "simultaneous impact (corner)", "impact at the section",
                           "branch point"]


def test_branches_legend_shows_only_what_is_drawn(make_continuation: Callable[..., Path]
                                                  ) -> None:
    path = make_continuation(stable=(1,) * 12, special=((4, "period-doubling"),))
    ax = figures.branches(path).axes[0]
    assert _legend(ax) == ["stable", "period doubling"]
    assert not [line for line in _lines(ax, "branch-") if line.get_linestyle() == "--"]


def test_branches_over_a_sweep(cont_file: Path, comparable_sweep: Path) -> None:
    sweep = read_run(comparable_sweep).sweep
    assert sweep is not None
    fig = figures.branches(cont_file, over=comparable_sweep, site=3)
    (ax,) = fig.axes
    first = ax.get_lines()[0]  # drawn first, under the branches
    assert first.get_gid() == "bifurcation-3" and first.get_color() == figures.OVER_COLOUR
    np.testing.assert_array_equal(first.get_xdata(), np.repeat(sweep.values, 5))
    np.testing.assert_array_equal(first.get_ydata(), sweep.x[:, :, 2].ravel())
    assert _legend(ax)[0] == "sweep"
    assert figures.metadata(fig)["Source"] == f"{cont_file}\n{comparable_sweep}"


def test_branches_refuse_a_sweep_of_another_parameter(cont_file: Path, make_run: MakeRun
                                                      ) -> None:
    omega = make_run("omega.h5", n=N, strobe=False, events=False,
                     sweep={"parameter": "omega"})
    with pytest.raises(figures.FigureError, match="a sweep over omega, the continuation "
                                                  "follows amplitude"):
        figures.branches(cont_file, over=omega)


def test_branches_refuse_a_sweep_of_another_chain(cont_file: Path, make_run: MakeRun) -> None:
    other_n = make_run("n4.h5", n=4, strobe=False, events=False, sweep=True)
    with pytest.raises(figures.FigureError, match="a chain of 4 oscillators"):
        figures.branches(cont_file, over=other_n)
    other_b = make_run("b.h5", n=N, strobe=False, events=False, sweep=True, omega=1.6)
    with pytest.raises(figures.FigureError, match=r"differs from the continuation in omega "
                                                  r"\(1.6, not 1.5\)"):
        figures.branches(cont_file, over=other_b)
    other_phase = make_run("p.h5", n=N, strobe=False, events=False, sweep=True, phase=0.5)
    with pytest.raises(figures.FigureError, match="section phase"):
        figures.branches(cont_file, over=other_phase)
    two_d = make_run("2d.h5", n=N, strobe=False, events=False,
                     sweep={"parameter2": "omega"})
    with pytest.raises(figures.FigureError, match="2-D sweep"):
        figures.branches(cont_file, over=two_d)


def test_branches_site_and_empty_continuation(cont_file: Path,
                                              make_continuation: Callable[..., Path]) -> None:
    with pytest.raises(figures.FigureError, match="site 4 is outside 1..3"):
        figures.branches(cont_file, site=4)
    empty = make_continuation("empty.h5", values=(), branch=(), period=(), stable=(),
                              special=())
    for draw in (figures.branches, figures.multipliers):
        with pytest.raises(figures.FigureError, match=re.escape(f"holds no orbit ({END_REASON})")):
            draw(empty)


def test_multipliers_are_the_largest_moduli(cont_file: Path) -> None:
    cont = read_continuation(cont_file)
    fig = figures.multipliers(cont_file)
    (ax,) = fig.axes
    modulus = np.abs(cont.multipliers).max(axis=1)
    lines = _lines(ax, "branch-")
    assert len(lines) == 4  # (branch 0, 1) x (stable, unstable)
    for line in lines:
        gid = str(line.get_gid())
        points = list(RUNS[gid])
        np.testing.assert_array_equal(line.get_xdata(), cont.values[points])
        np.testing.assert_array_equal(line.get_ydata(), modulus[points])
        assert line.get_linestyle() == ("-" if gid.endswith("-stable") else "--")
    (unit,) = _lines(ax, "unit")
    assert list(unit.get_ydata()) == [1.0, 1.0]
    markers = _markers(ax)
    assert sum(len(xy) for xy in markers.values()) == len(SPECIAL)  # one per special point
    for index, kind in SPECIAL:
        np.testing.assert_array_equal(markers[kind], [[VALUES[index], modulus[index]]])
    assert ax.get_yscale() == "linear"  # moduli from 0.81 to 2.6
    assert _legend(ax) == ["stable", "unstable", "fold", "period doubling", "Neimark-Sacker",
                           "grazing", "simultaneous impact (corner)", "impact at the section",
                           "branch point"]


def test_multipliers_on_a_log_scale_when_they_span_decades(cont_file: Path) -> None:
    with h5py.File(cont_file, "r+") as f:
        f["continuation/multipliers_re"][11, 0] = 250.0
    ax = figures.multipliers(cont_file).axes[0]
    assert ax.get_yscale() == "log"


def test_labels_units_and_axes(cont_file: Path, comparable_sweep: Path) -> None:
    """Axis labels ``name $symbol$ [unit]``, the units the file's; ``ax=`` draws there."""
    made = {"branches": figures.branches(cont_file, over=comparable_sweep, site=2),
            "multipliers": figures.multipliers(cont_file)}
    for name, fig in made.items():
        ax = fig.axes[0]
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            assert re.fullmatch(r"[^\[\]]+ \[[^\[\]]+\]", label), (name, label)
        assert ax.get_xlabel() == "drive amplitude $A$ [length]"
        assert "$A$" not in ax.get_title() and END_REASON in ax.get_title()
    assert made["branches"].axes[0].get_ylabel() == \
        "displacement at the section $x_{2}$ [length]"
    assert made["multipliers"].axes[0].get_ylabel() == \
        "largest Floquet multiplier $|\\mu|_{\\max}$ [1]"
    fig = Figure()
    left, right = fig.subplots(1, 2)
    assert figures.branches(cont_file, ax=right) is fig
    assert figures.multipliers(cont_file, ax=left) is fig
    assert _lines(right, "branch-") and _lines(left, "branch-")


# -------------------------------------------------------------------------------------- cli


def test_cli_writes_the_figures(cont_file: Path, comparable_sweep: Path,
                                tmp_path: Path) -> None:
    from PIL import Image

    out = tmp_path / "branches.png"
    assert main(["branches", str(cont_file), "--over", str(comparable_sweep), "--site", "2",
                 "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with Image.open(out) as image:
        assert image.text["Source"] == f"{cont_file}\n{comparable_sweep}"
    out = tmp_path / "multipliers.pdf"
    assert main(["multipliers", str(cont_file), "-o", str(out)]) == 0
    assert out.read_bytes()[:5] == b"%PDF-"
    assert main(["all", str(cont_file), "-o", str(tmp_path / "all" / "c")]) == 0
    assert sorted(p.name for p in (tmp_path / "all").iterdir()) == [
        "c_branches.png", "c_multipliers.png"]


def _refused(argv: list[str], message: str, out: Path,
             capsys: pytest.CaptureFixture[str]) -> None:
    assert main([*argv, "-o", str(out)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("impactchain: error: "), lines
    assert message in lines[0]
    assert not out.exists()


def test_cli_refuses_a_sweep_of_another_parameter(cont_file: Path, make_run: MakeRun,
                                                  tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    omega = make_run("omega.h5", n=N, strobe=False, events=False,
                     sweep={"parameter": "omega"})
    _refused(["branches", str(cont_file), "--over", str(omega)],
             "a sweep over omega, the continuation follows amplitude", tmp_path / "b.png",
             capsys)


def test_cli_errors(cont_file: Path, sweep_file: Path, tmp_path: Path,
                    capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "x.png"
    _refused(["branches", str(sweep_file)], "no /continuation, needed by branches (this is "
             "not a continuation file)", out, capsys)
    _refused(["multipliers", str(sweep_file)], "no /continuation, needed by multipliers",
             out, capsys)
    _refused(["branches", str(cont_file), "--over", str(cont_file)],
             "no /sweep, needed by branches --over (this is not a parameter-sweep file)", out,
             capsys)
    _refused(["branches", str(cont_file), "--site", "5"], "site 5 is outside 1..3", out,
             capsys)
    with pytest.raises(SystemExit) as exit_info:
        main(["branches", str(cont_file), "--site", "0", "-o", str(out)])
    assert exit_info.value.code == 2
