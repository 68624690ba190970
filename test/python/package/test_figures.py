"""impactchain.figures: the axes hold the data they claim to show."""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import LineCollection, PathCollection
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.text import Text

from impactchain import figures
from impactchain.analysis import period_label
from impactchain.io import Run, SchemaError, read_run
from impactchain.shockwave import build_shock_waves
from test_continuation import write_continuation

MakeRun = Callable[..., Path]


def _lines(ax: Axes, gid_prefix: str) -> list[Line2D]:
    return [line for line in ax.get_lines() if (line.get_gid() or "").startswith(gid_prefix)]


def _walls(ax: Axes) -> list[float]:
    return sorted(float(line.get_xdata()[0]) for line in _lines(ax, "wall"))


def _scatter(ax: Axes, gid: str) -> PathCollection:
    (points,) = [c for c in ax.collections if isinstance(c, PathCollection) and c.get_gid() == gid]
    return points


def _plots(fig: Figure) -> list[Axes]:
    """The axes of a figure that hold data (not its colour bars)."""
    return [a for a in fig.axes if a.get_label() != "<colorbar>"]


def _colorbars(fig: Figure) -> list[Axes]:
    return [a for a in fig.axes if a.get_label() == "<colorbar>"]


def _axes(fig: Figure, label: str) -> Axes:
    (ax,) = [a for a in fig.axes if a.get_label() == label]
    return ax


# --------------------------------------------------------------------- space-amplitude


def test_space_amplitude_lines_are_the_strobe_rows(make_run: MakeRun) -> None:
    run = read_run(make_run(n=5, records=12))
    fig = figures.space_amplitude([run])
    assert isinstance(fig, Figure)
    (ax,) = fig.axes
    lines = _lines(ax, "strobe-0")
    assert run.strobe is not None and len(lines) == 12
    for line, row in zip(lines, run.strobe.x):
        np.testing.assert_array_equal(line.get_xdata(), run.params.equilibrium)
        np.testing.assert_array_equal(line.get_ydata(), row)


def test_space_amplitude_last_cycles(make_run: MakeRun) -> None:
    run = read_run(make_run(records=12))
    ax = figures.space_amplitude([run], cycles=5).axes[0]
    lines = _lines(ax, "strobe-0")
    assert run.strobe is not None and len(lines) == 5
    np.testing.assert_array_equal(lines[-1].get_ydata(), run.strobe.x[-1])
    np.testing.assert_array_equal(lines[0].get_ydata(), run.strobe.x[-5])


def test_space_amplitude_walls_follow_the_boundary(make_run: MakeRun) -> None:
    spacing = np.array([1.0, 0.8, 1.2, 1.0, 1.1])
    fixed = read_run(make_run("fixed.h5", spacing=spacing))
    free = read_run(make_run("free.h5", boundary="free"))
    assert _walls(figures.space_amplitude([fixed]).axes[0]) == pytest.approx([0.0, 5.1])
    assert _walls(figures.space_amplitude([free]).axes[0]) == []


def test_space_amplitude_period_labels(make_run: MakeRun) -> None:
    ax = figures.space_amplitude([read_run(make_run(n=6))]).axes[0]
    labels = [t.get_text() for t in ax.texts if t.get_gid() == "period"]
    assert labels == ["P1", "P2", "P4", "ap", "P1", "P2"]


def test_space_amplitude_shows_the_stored_periods_not_the_records(make_run: MakeRun) -> None:
    """The labels are /strobe/period as stored, even where the records shown would suggest
    other periods (the record of oscillator i has period PERIODS[i], conftest): no
    period is computed in Python."""
    stored = [3, 0, 1, 2]  # the records have periods 1, 2, 4 and none
    run = read_run(make_run(n=4, records=20, periods=stored))
    for cycles in (None, 6):
        ax = figures.space_amplitude([run], cycles=cycles).axes[0]
        labels = [t.get_text() for t in ax.texts if t.get_gid() == "period"]
        assert labels == ["P3", "ap", "P1", "P2"]


def test_space_amplitude_labels_only_stored_periods(make_run: MakeRun) -> None:
    run = read_run(make_run(n=4, records=20, periods=False))
    plain = figures.space_amplitude([run]).axes[0]
    assert [t for t in plain.texts if t.get_gid() == "period"] == []
    shown = figures.space_amplitude([read_run(make_run("p.h5", n=4))], periods="none").axes[0]
    assert [t for t in shown.texts if t.get_gid() == "period"] == []
    with pytest.raises(figures.FigureError, match="'file' or 'none'"):
        figures.space_amplitude([run], periods="detect")


def test_space_amplitude_overlays_runs_in_colours(make_run: MakeRun) -> None:
    runs = [read_run(make_run("a.h5")), read_run(make_run("b.h5", records=8))]
    ax = figures.space_amplitude(runs).axes[0]
    first, second = _lines(ax, "strobe-0"), _lines(ax, "strobe-1")
    assert (len(first), len(second)) == (30, 8)
    assert first[0].get_color() != second[0].get_color()
    legend = ax.get_legend()
    # the two files differ in nothing but their length: numbered, never named by file
    assert legend is not None and [t.get_text() for t in legend.get_texts()] == ["run 1",
                                                                                 "run 2"]


# ---------------------------------------------------------------- space-time-amplitude


def test_space_time_amplitude_panels_hold_the_records(make_run: MakeRun) -> None:
    run = read_run(make_run(n=4, records=25, first_cycle=100))
    fig = figures.space_time_amplitude(run, panel_cycles=10)
    assert len(fig.axes) == 3  # 10 + 10 + 5 records
    assert run.strobe is not None
    for p, ax in enumerate(fig.axes):
        lines = ax.get_lines()
        rows = run.strobe.x[10 * p:10 * (p + 1)]
        assert len(lines) == len(rows)
        for line, row, cycle in zip(lines, rows, run.strobe.cycle[10 * p:]):
            xs, ys, zs = line.get_data_3d()
            np.testing.assert_array_equal(xs, run.params.equilibrium)
            np.testing.assert_array_equal(ys, np.full(4, cycle))
            np.testing.assert_array_equal(zs, row)
        assert ax.get_ylim() == pytest.approx((100 + 10 * p, 110 + 10 * p))


def test_space_time_amplitude_panel_count_is_capped(make_run: MakeRun) -> None:
    run = read_run(make_run(n=3, records=100, events=False))
    assert len(figures.space_time_amplitude(run, panel_cycles=5).axes) == 8
    assert len(figures.space_time_amplitude(run, panel_cycles=5, panels=3).axes) == 3


# -------------------------------------------------------------------------- shock-wave


def _points_in(run: Run, side: str, window: tuple[float, float]) -> np.ndarray:
    assert run.events is not None
    p = run.params
    waves = build_shock_waves(run.events.time, run.events.site, p.n, p.drive_period)
    rows = [(p.site_positions[k], t / p.drive_period)
            for w in waves if w.side == side for t, k in zip(w.times, w.sites)]
    points = np.array(rows)
    keep = (points[:, 1] >= window[0]) & (points[:, 1] < window[1])
    return points[keep]


def test_shock_wave_scatter_is_the_constructed_waves(make_run: MakeRun) -> None:
    run = read_run(make_run(n=4, records=6, first_cycle=10))
    fig = figures.shock_wave(run, panel_cycles=3)
    assert len(fig.axes) == 4
    for p, start in enumerate((10, 13)):
        for side in ("left", "right"):
            ax = _axes(fig, f"shock-{side}-{p}")
            offsets = np.asarray(_scatter(ax, "collisions").get_offsets())
            expected = _points_in(run, side, (start, start + 3))
            assert len(expected) > 0
            np.testing.assert_allclose(offsets, expected)
            assert ax.get_ylim() == pytest.approx((start, start + 3))
            assert _walls(ax) == pytest.approx([0.0, 5.0])
            lines = [c for c in ax.collections if isinstance(c, LineCollection)]
            assert len(lines) == 1 and len(lines[0].get_segments()) > 0


def test_shock_wave_right_waves_above_left_waves(make_run: MakeRun) -> None:
    fig = figures.shock_wave(read_run(make_run(records=4)), panel_cycles=4)
    upper, lower = _axes(fig, "shock-right-0"), _axes(fig, "shock-left-0")
    assert upper.get_position().y0 >= lower.get_position().y1 - 1e-9


def test_shock_wave_time_shares_the_section_phase(make_run: MakeRun) -> None:
    run = read_run(make_run(records=4, first_cycle=0, phase=np.pi))
    fig = figures.shock_wave(run, panel_cycles=2)
    assert _axes(fig, "shock-left-1").get_ylim() == pytest.approx((2.5, 4.5))
    sta = figures.space_time_amplitude(run, panel_cycles=2)
    assert sta.axes[1].get_ylim() == pytest.approx((2.5, 4.5))


def test_shock_wave_needs_events(make_run: MakeRun) -> None:
    with pytest.raises(figures.FigureError, match="no events"):
        figures.shock_wave(read_run(make_run(events=False)))


# ---------------------------------------------------------------------------- poincare


def test_poincare_points_are_one_oscillator(make_run: MakeRun) -> None:
    run = read_run(make_run(n=4, records=20))
    ax = figures.poincare(run, site=3, cycles=7).axes[0]
    assert run.strobe is not None
    np.testing.assert_array_equal(
        _scatter(ax, "section").get_offsets(),
        np.column_stack((run.strobe.x[-7:, 2], run.strobe.v[-7:, 2])),
    )
    with pytest.raises(figures.FigureError, match="site 5 is outside 1..4"):
        figures.poincare(run, site=5)


# ------------------------------------------------------------------------- bifurcation


def test_bifurcation_points_are_the_sweep_records(sweep_file: Path) -> None:
    run = read_run(sweep_file)
    fig = figures.bifurcation(run)
    assert run.sweep is not None and len(fig.axes) == run.params.n
    for site, ax in enumerate(fig.axes, start=1):
        (line,) = _lines(ax, f"bifurcation-{site}")
        np.testing.assert_array_equal(line.get_xdata(), np.repeat(run.sweep.values, 5))
        np.testing.assert_array_equal(line.get_ydata(), run.sweep.x[:, :, site - 1].ravel())


def test_bifurcation_selected_sites(sweep_file: Path) -> None:
    fig = figures.bifurcation(read_run(sweep_file), sites=[1, 3])
    assert [a.get_title() for a in fig.axes] == ["oscillator 1", "oscillator 3"]


def test_bifurcation_rejects_two_parameter_sweep(make_run: MakeRun) -> None:
    run = read_run(make_run(sweep={"parameter2": "omega"}))
    with pytest.raises(figures.FigureError, match="2-D sweep"):
        figures.bifurcation(run)


# ---------------------------------------------------------------------------- lyapunov


def test_lyapunov_lines_are_the_largest_exponents(sweep_file: Path) -> None:
    run = read_run(sweep_file)
    fig = figures.lyapunov([run], k=4)
    (ax,) = _plots(fig)
    assert run.sweep is not None and run.sweep.exponents is not None
    lines = _lines(ax, "exponent-")
    assert len(lines) == 4
    for j, line in enumerate(lines):
        np.testing.assert_array_equal(line.get_xdata(), run.sweep.values)
        np.testing.assert_array_equal(line.get_ydata(), run.sweep.exponents[:, j])
    (zero,) = _lines(ax, "zero")
    assert list(zero.get_ydata()) == [0.0, 0.0]
    assert "bits/cycle" in ax.get_ylabel()


def test_lyapunov_with_bifurcation_panel(sweep_file: Path) -> None:
    run = read_run(sweep_file)
    top, bottom = _plots(figures.lyapunov([run], k=20, with_bifurcation=True))
    assert len(_lines(top, "bifurcation-1")) == 1
    assert len(_lines(bottom, "exponent-")) == 6  # only 6 stored
    assert top.get_position().y0 > bottom.get_position().y0


# ------------------------------------------------------------------------ ky-dimension


def test_ky_dimension_draws_the_stored_values(sweep_file: Path) -> None:
    """/sweep/ky_dimension as stored. The fixture's values are not those of its exponents
    (point 0: 0.5, 0.2, -0.1, -0.4, -0.7, -1.0 would give 4 + 0.2/0.7), so a figure that
    computed them would fail here."""
    run = read_run(sweep_file)
    (ax,) = figures.ky_dimension([run]).axes
    (line,) = _lines(ax, "ky")
    assert run.sweep is not None and run.sweep.ky_dimension is not None
    np.testing.assert_array_equal(line.get_ydata(), run.sweep.ky_dimension)
    assert line.get_ydata()[0] != pytest.approx(4 + 0.2 / 0.7)


def test_ky_dimension_is_never_computed_from_the_exponents(make_run: MakeRun) -> None:
    run = read_run(make_run(n=3, sweep={"ky_dimension": False}))
    assert run.sweep is not None and run.sweep.exponents is not None
    with pytest.raises(figures.FigureError, match="no Kaplan-Yorke dimensions"):
        figures.ky_dimension([run])


def _partial_sweep(make_run: MakeRun, name: str, k: int, ky: list[float]) -> Run:
    """A sweep of n = 4 (2n = 8) with k exponents per point and the given stored
    dimensions (the simulator stores k where the partial sums never turned negative)."""
    path = make_run(name, n=4, strobe=False, events=False,
                    sweep={"points": len(ky), "exponents": k})
    with h5py.File(path, "r+") as f:
        f["sweep/ky_dimension"][...] = ky
    return read_run(path)


def test_ky_dimension_from_a_partial_spectrum_is_a_lower_bound(make_run: MakeRun) -> None:
    """Issue 32, 8: with vectors = 1 the stored 1.0 wherever lambda1 >= 0 is a lower bound
    (docs/model.md 7.5): those points are marked and named in the legend, and the title says
    how many of the 2n exponents were computed."""
    run = _partial_sweep(make_run, "one.h5", 1, [0.0, 1.0, 1.0, 0.0, 1.0])
    (ax,) = figures.ky_dimension([run]).axes
    (line,) = _lines(ax, "ky")
    np.testing.assert_array_equal(line.get_ydata(), [0.0, 1.0, 1.0, 0.0, 1.0])
    (bound,) = _lines(ax, "lower-bound")
    assert run.sweep is not None
    np.testing.assert_array_equal(bound.get_xdata(), run.sweep.values[[1, 2, 4]])
    np.testing.assert_array_equal(bound.get_ydata(), [1.0, 1.0, 1.0])
    legend = ax.get_legend()
    assert legend is not None
    assert [t.get_text() for t in legend.get_texts()] == ["lower bound (1 of 8 exponents)"]
    assert "from 1 of 8 exponents; open triangles: lower bounds" in ax.get_title()


def test_ky_dimension_below_the_partial_count_is_not_a_bound(make_run: MakeRun) -> None:
    """A partial sum that turned negative within the k exponents gives the dimension itself:
    nothing marked, but the title still says the spectrum is partial; a full spectrum says
    nothing of it."""
    run = _partial_sweep(make_run, "three.h5", 3, [0.0, 1.5, 2.9])
    (ax,) = figures.ky_dimension([run]).axes
    assert not _lines(ax, "lower-bound") and ax.get_legend() is None
    assert "from 3 of 8 exponents" in ax.get_title()
    assert "lower bound" not in ax.get_title()
    full = _partial_sweep(make_run, "full.h5", 8, [0.0, 8.0, 2.5])
    (ax,) = figures.ky_dimension([full]).axes
    assert not _lines(ax, "lower-bound") and "exponents" not in ax.get_title()


def test_ky_dimension_lower_bounds_on_a_2d_sweep(make_run: MakeRun) -> None:
    path = make_run("two.h5", n=4, strobe=False, events=False,
                    sweep={"points": 4, "exponents": 2, "parameter2": "omega"})
    with h5py.File(path, "r+") as f:
        f["sweep/ky_dimension"][...] = [2.0, 1.3, 0.0, 2.0]
    ax = _plots(figures.ky_dimension([read_run(path)]))[0]
    bound = _scatter(ax, "lower-bound")
    assert len(bound.get_offsets()) == 2
    assert "from 2 of 8 exponents" in ax.get_title()


def test_lyapunov_title_says_how_many_of_the_spectrum(make_run: MakeRun) -> None:
    """The exponents figure of a partial spectrum: 'the largest 1 of 8', not 'all 1'."""
    run = _partial_sweep(make_run, "one.h5", 1, [0.0, 1.0, 1.0])
    title = figures.lyapunov([run]).get_suptitle()
    assert title.startswith("the largest 1 of 8 Lyapunov exponents"), title
    full = _partial_sweep(make_run, "full.h5", 8, [0.0, 8.0, 2.5])
    assert figures.lyapunov([full]).get_suptitle().startswith("all 8 Lyapunov exponents")


def test_spectrum_of_a_partial_spectrum_says_lower_bound(make_run: MakeRun) -> None:
    path = make_run("partial.h5", n=4, lyapunov=True)
    with h5py.File(path, "r+") as f:
        g = f["lyapunov"]
        for name in ("exponents", "exponents_per_time", "stderr", "running"):
            data, attrs = g[name][..., :2], dict(g[name].attrs)
            del g[name]
            g[name] = data
            g[name].attrs.update(attrs)
        g.attrs["ky_dimension"] = 2.0
    left = _plots(figures.spectrum(read_run(path)))[0]
    assert left.get_title().startswith("$D_{KY}$ $\\geq$ 2.000 (a lower bound: 2 of 8 "
                                       "exponents)"), left.get_title()


# ---------------------------------------------------------------------------- spectrum


def test_spectrum_shows_exponents_with_error_bars(run_file: Path) -> None:
    run = read_run(run_file)
    left, right = _plots(figures.spectrum(run))
    assert run.lyapunov is not None and run.strobe is not None
    (bars,) = left.containers
    points, _, (vertical,) = bars.lines
    assert points.get_gid() == "spectrum"
    np.testing.assert_array_equal(points.get_xdata(), np.arange(1, 9))
    np.testing.assert_array_equal(points.get_ydata(), run.lyapunov.exponents)
    spans = [seg[:, 1] for seg in vertical.get_segments()]
    np.testing.assert_allclose([hi - lo for lo, hi in spans], 2 * run.lyapunov.stderr)
    # the stored dimension (the fixture's 3.5), not that of the exponents (4.44)
    assert left.get_title().startswith("$D_{KY}$ = 3.500,")
    running = _lines(right, "running-")
    assert len(running) == 8
    np.testing.assert_array_equal(running[0].get_xdata(), run.strobe.cycle)
    np.testing.assert_array_equal(running[2].get_ydata(), run.lyapunov.running[:, 2])


def test_spectrum_plots_decimated_running_estimates_at_their_cycles(run_file: Path) -> None:
    """A long run keeps every d-th running estimate: /lyapunov/running_cycle places them."""
    import h5py

    with h5py.File(run_file, "r+") as f:
        running = f["lyapunov/running"][:]
        del f["lyapunov/running"]
        f["lyapunov/running"] = running[1::2]
        f["lyapunov/running_cycle"] = f["strobe/cycle"][1::2]
    run = read_run(run_file)
    assert run.lyapunov is not None and run.lyapunov.running_cycle is not None
    running = _lines(_plots(figures.spectrum(run))[1], "running-")
    np.testing.assert_array_equal(running[0].get_xdata(), run.lyapunov.running_cycle)
    np.testing.assert_array_equal(running[0].get_ydata(), run.lyapunov.running[:, 0])


# ------------------------------------------------------------------------------ general


def test_figures_do_not_use_pyplot(run_file: Path) -> None:
    import matplotlib.pyplot as plt

    figures.space_amplitude([read_run(run_file)])
    assert plt.get_fignums() == []


def test_shock_wave_keeps_history_before_the_start(make_run: MakeRun) -> None:
    period = 2 * np.pi / 1.5
    time = np.array([9.9, 10.2, 10.4, 10.5]) * period
    run = read_run(make_run(n=4, records=4, first_cycle=9,
                            events={"time": time, "site": [0, 1, 2, 3]}))
    fig = figures.shock_wave(run, panel_cycles=2, start=10)
    assert len(fig.axes) == 4  # panels [10, 12) and [12, 14), two axes each
    offsets = np.asarray(_scatter(_axes(fig, "shock-left-0"), "collisions").get_offsets())
    np.testing.assert_allclose(offsets, [[1.0, 10.2], [2.0, 10.4], [3.0, 10.5]])
    assert len(_scatter(_axes(fig, "shock-right-0"), "collisions").get_offsets()) == 0


def test_shock_wave_of_a_free_chain_is_empty(make_run: MakeRun, tmp_path: Path) -> None:
    events = {"time": [0.1, 0.2, 0.3], "site": [1, 2, 3]}
    run = read_run(make_run(boundary="free", records=3, first_cycle=0, events=events))
    fig = figures.shock_wave(run)
    ax = _axes(fig, "shock-left-0")
    assert len(_scatter(ax, "collisions").get_offsets()) == 0 and _walls(ax) == []
    fig.savefig(tmp_path / "empty.png")


def test_space_time_amplitude_from_a_start_cycle(make_run: MakeRun) -> None:
    run = read_run(make_run(records=30, first_cycle=100, events=False))
    fig = figures.space_time_amplitude(run, panel_cycles=10, start=110)
    assert [ax.get_ylim() for ax in fig.axes] == [(110, 120), (120, 130)]
    with pytest.raises(figures.FigureError, match="start cycle 5 is outside"):
        figures.space_time_amplitude(run, start=5)


def test_shock_wave_says_when_no_event_falls_in_the_panels(make_run: MakeRun) -> None:
    period = 2 * np.pi / 1.5
    run = read_run(make_run(records=4, first_cycle=10,
                            events={"time": [90.1 * period, 90.2 * period], "site": [0, 1]}))
    title = figures.shock_wave(run).get_suptitle()
    assert "no collision in the shown cycles: the events span t/T = 90.1 to 90.2" in title
    normal = figures.shock_wave(read_run(make_run("ok.h5", records=4)))
    assert "no collision" not in normal.get_suptitle()


def test_ky_dimension_overlay_labels_the_differing_parameter(make_run: MakeRun) -> None:
    runs = [read_run(make_run(f"s{j}.h5", sweep=True, omega=w)) for j, w in
            enumerate((1.5, 1.9))]
    (ax,) = figures.ky_dimension(runs).axes
    labels = [text.get_text() for text in ax.get_legend().get_texts()]
    assert labels == ["$\\omega$ = 1.5", "$\\omega$ = 1.9"]
    assert "omega" not in ax.get_title() and "\\omega" not in ax.get_title()


# ------------------------------------------------------------- what a referee checks


def _colorbar_of(cax: Axes) -> Any:
    return cax._colorbar  # type: ignore[attr-defined]  # set by matplotlib's Colorbar


def _all_labels(fig: Figure) -> list[str]:
    """Every axis label of a figure, colour bars included (3-D: the z label too)."""
    labels = []
    for ax in fig.axes:
        texts = [ax.get_xlabel(), ax.get_ylabel()]
        if hasattr(ax, "get_zlabel"):
            texts.append(ax.get_zlabel())
        labels.extend(t for t in texts if t)
    return labels


def _every_figure(run_file: Path, sweep_file: Path) -> dict[str, Figure]:
    run, sweep = read_run(run_file), read_run(sweep_file)
    return {
        "space-amplitude": figures.space_amplitude([run]),
        "space-time-amplitude": figures.space_time_amplitude(run, panel_cycles=10),
        "shock-wave": figures.shock_wave(run, panel_cycles=10),
        "poincare": figures.poincare(run),
        "bifurcation": figures.bifurcation(sweep),
        "lyapunov": figures.lyapunov([sweep], with_bifurcation=True),
        "ky-dimension": figures.ky_dimension([sweep]),
        "spectrum": figures.spectrum(run),
    }


def test_every_axis_label_ends_in_a_unit(run_file: Path, sweep_file: Path) -> None:
    """The one notation: ``name $symbol$ [unit]``, ``[1]`` when dimensionless."""
    for name, fig in _every_figure(run_file, sweep_file).items():
        labels = _all_labels(fig)
        assert labels, name
        for label in labels:
            assert re.fullmatch(r"[^\[\]]+ \[[^\[\]]+\]", label), (name, label)


def test_units_are_those_of_the_file(run_file: Path, sweep_file: Path) -> None:
    """The fixture's units ('a', 'a/time', 'bits/cycle', 'cycles') are not the simulator's:
    labels that show them come from the file, not from a table."""
    made = _every_figure(run_file, sweep_file)
    (ax,) = made["space-amplitude"].axes
    assert ax.get_ylabel() == "displacement at the section $x_i$ [a]"
    assert ax.get_xlabel() == "equilibrium position [a]"
    poincare_ax, bar = made["poincare"].axes
    assert poincare_ax.get_ylabel() == "velocity $v_{1}$ [a/time]"
    assert bar.get_ylabel() == "cycle $c$ [cycles]"
    exponents = _plots(made["lyapunov"])[1]
    assert exponents.get_ylabel() == "Lyapunov exponents $\\lambda_j$ [bits/cycle]"
    assert exponents.get_xlabel() == "drive amplitude $A$ [length]"
    assert _plots(made["ky-dimension"])[0].get_ylabel() == \
        "Kaplan-Yorke dimension $D_{KY}$ [1]"


def test_colour_bars_wherever_colour_encodes_a_number(run_file: Path, sweep_file: Path,
                                                     make_run: MakeRun) -> None:
    made = _every_figure(run_file, sweep_file)
    # colour by exponent index: one bar, ticks 1..k, the lines' colours are the bar's
    for name, axis in (("lyapunov", 1), ("spectrum", 1)):
        fig = made[name]
        (cax,) = _colorbars(fig)
        assert cax.get_ylabel() == "exponent index $j$ [1]"
        bar = _colorbar_of(cax)
        lines = _lines(_plots(fig)[axis], "exponent-" if name == "lyapunov" else "running-")
        assert len(lines) == 6 if name == "lyapunov" else 8
        assert list(cax.get_yticks()) == list(range(1, len(lines) + 1))
        for j, line in enumerate(lines, start=1):
            np.testing.assert_allclose(to_rgba(line.get_color()), bar.mappable.to_rgba(j))
        assert len({to_rgba(line.get_color()) for line in lines}) == len(lines)
    # colour by cycle, and by dimension over a 2-D sweep
    (cax,) = _colorbars(made["poincare"])
    assert "cycle" in cax.get_ylabel()
    two_d = figures.ky_dimension([read_run(make_run("2d.h5", sweep={"parameter2": "omega"}))])
    (cax,) = _colorbars(two_d)
    assert cax.get_ylabel() == "Kaplan-Yorke dimension $D_{KY}$ [1]"
    # colour that only tells runs or sides apart: no colour bar
    for name in ("space-amplitude", "space-time-amplitude", "shock-wave", "bifurcation",
                 "ky-dimension"):
        assert _colorbars(made[name]) == [], name


def test_lyapunov_draws_the_stored_standard_errors_as_bands(sweep_file: Path) -> None:
    run = read_run(sweep_file)
    assert run.sweep is not None and run.sweep.stderr is not None
    ax = _plots(figures.lyapunov([run], k=3))[0]
    sweep = run.sweep
    assert sweep.exponents is not None and sweep.stderr is not None
    for j in range(3):
        (band,) = [c for c in ax.collections if c.get_gid() == f"stderr-{j + 1}"]
        vertices = band.get_paths()[0].vertices
        for value, exponent, error in zip(sweep.values, sweep.exponents[:, j],
                                          sweep.stderr[:, j]):
            at = vertices[np.isclose(vertices[:, 0], value), 1]
            assert at.min() == pytest.approx(exponent - error)
            assert at.max() == pytest.approx(exponent + error)
    assert not [c for c in ax.collections if c.get_gid() == "stderr-4"]


def test_lyapunov_bars_for_a_sweep_back_and_forth(make_run: MakeRun) -> None:
    path = make_run(strobe=False, events=False, sweep=True)
    with h5py.File(path, "r+") as f:
        values = f["sweep/values"][:]
        f["sweep/values"][...] = np.concatenate((values[::2], values[1::2]))  # not monotonic
        f["sweep/stderr"][...] = np.linspace(0.01, 0.07, values.size)[:, None]
    run = read_run(path)
    assert run.sweep is not None and run.sweep.stderr is not None
    ax = _plots(figures.lyapunov([run], k=2))[0]
    (bars,) = [c for c in ax.collections if c.get_gid() == "stderr-1"]
    spans = [seg[1, 1] - seg[0, 1] for seg in bars.get_segments()]
    np.testing.assert_allclose(sorted(spans), sorted(2 * run.sweep.stderr[:, 0]))


def test_spectrum_panels_share_their_range(run_file: Path) -> None:
    left, right = _plots(figures.spectrum(read_run(run_file)))
    assert left.get_ylim() == right.get_ylim()


def test_compared_panels_share_their_scales(make_run: MakeRun) -> None:
    """Two sweeps of different exponent ranges: one y range for all exponent panels, one
    for all bifurcation panels; bifurcation panels of several oscillators share theirs."""
    paths = [make_run(f"s{j}.h5", strobe=False, events=False, sweep=True, omega=w)
             for j, w in enumerate((1.5, 1.9))]
    with h5py.File(paths[1], "r+") as f:
        f["sweep/exponents"][...] = 3.0 * f["sweep/exponents"][:]
        f["sweep/x"][...] = -2.0 * f["sweep/x"][:]
    runs = [read_run(p) for p in paths]
    tops_and_bottoms = _plots(figures.lyapunov(runs, k=6, with_bifurcation=True))
    tops, bottoms = tops_and_bottoms[:2], tops_and_bottoms[2:]
    assert tops[0].get_ylim() == tops[1].get_ylim()
    assert bottoms[0].get_ylim() == bottoms[1].get_ylim()
    low, high = bottoms[0].get_ylim()
    assert runs[1].sweep is not None and runs[1].sweep.exponents is not None
    assert low <= runs[1].sweep.exponents.min() - 0.01 and high >= 0.5 + 0.01
    panels = _plots(figures.bifurcation(runs[1]))
    assert len({ax.get_ylim() for ax in panels}) == 1
    run = read_run(make_run("long.h5", records=30, events=False))
    assert len({ax.get_zlim() for ax in figures.space_time_amplitude(run, 10).axes}) == 1


def test_legends_name_seeds_not_files(make_run: MakeRun) -> None:
    red = read_run(make_run("fig3_red.h5", seed=1))
    green = read_run(make_run("fig3_green.h5", seed=4))
    ax = figures.space_amplitude([red, green]).axes[0]
    assert [t.get_text() for t in ax.get_legend().get_texts()] == ["seed 1", "seed 4"]
    assert figures.run_labels([red, green]) == ["seed 1", "seed 4"]
    # a parameter that differs names the runs before the seed does
    other = read_run(make_run("fig3_blue.h5", seed=1, omega=1.9))
    assert figures.run_labels([red, other]) == ["$\\omega$ = 1.5", "$\\omega$ = 1.9"]
    # given labels win; nothing differs: numbered
    mine = figures.space_amplitude([red, green], labels=["left", "right"]).axes[0]
    assert [t.get_text() for t in mine.get_legend().get_texts()] == ["left", "right"]
    twin = read_run(make_run("twin.h5", seed=1))
    assert figures.run_labels([red, twin]) == ["run 1", "run 2"]
    for labels in (figures.run_labels([red, green, other, twin]),):
        assert not any("fig3" in label or ".h5" in label for label in labels)


@pytest.mark.parametrize("name", ["space-amplitude", "space-time-amplitude", "shock-wave",
                                  "poincare", "bifurcation", "lyapunov", "ky-dimension",
                                  "spectrum"])
def test_ax_draws_into_the_given_axes(name: str, run_file: Path, sweep_file: Path) -> None:
    run, sweep = read_run(run_file), read_run(sweep_file)
    fig = Figure()
    if name == "space-time-amplitude":
        axes = [fig.add_subplot(1, 3, i + 1, projection="3d") for i in range(3)]
        made = figures.space_time_amplitude(run, panel_cycles=10, ax=axes)
    elif name == "shock-wave":
        axes = list(fig.subplots(2, 3).T.ravel())  # (upper, lower) of each of 3 panels
        made = figures.shock_wave(run, panel_cycles=10, ax=axes)
    elif name == "bifurcation":
        axes = list(fig.subplots(2, 2).ravel())
        made = figures.bifurcation(sweep, ax=axes)
    elif name == "lyapunov":
        axes = list(fig.subplots(2, 1))
        made = figures.lyapunov(sweep, with_bifurcation=True, ax=axes)
    elif name == "spectrum":
        axes = list(fig.subplots(1, 2))
        made = figures.spectrum(run, ax=axes)
    else:
        axes = [fig.add_subplot()]
        draw = {"space-amplitude": figures.space_amplitude, "poincare": figures.poincare,
                "ky-dimension": figures.ky_dimension}[name]
        made = draw(sweep if name == "ky-dimension" else run, ax=axes[0])
    assert made is fig
    assert set(_plots(fig)) == set(axes)  # no new data axes, only colour bars
    for ax in axes:
        assert ax.has_data(), (name, ax)
    assert fig.get_suptitle() == ""  # the caller's figure: its title is the caller's


def test_ax_of_the_wrong_count_is_an_error(run_file: Path, sweep_file: Path) -> None:
    fig = Figure()
    with pytest.raises(figures.FigureError, match="draws into 4 axes, 2 given"):
        figures.bifurcation(read_run(sweep_file), ax=fig.subplots(1, 2))
    with pytest.raises(figures.FigureError, match="3-D axes"):
        figures.space_time_amplitude(read_run(run_file), panel_cycles=30,
                                     ax=[fig.add_subplot()])


def test_paths_and_in_memory_results_are_accepted(run_file: Path, sweep_file: Path) -> None:
    from_path = figures.poincare(str(run_file), site=2)
    np.testing.assert_array_equal(
        _scatter(from_path.axes[0], "section").get_offsets(),
        _scatter(figures.poincare(read_run(run_file), site=2).axes[0], "section").get_offsets())
    figures.lyapunov(sweep_file)  # a single path, not a list
    with pytest.raises(SchemaError, match="no /sweep, needed by lyapunov"):
        figures.lyapunov(run_file)

    class InMemory:  # the protocol: anything with to_run()
        def to_run(self) -> Run:
            return read_run(run_file)

    ax = figures.space_amplitude(InMemory()).axes[0]
    assert len(_lines(ax, "strobe-0")) == 30
    with pytest.raises(TypeError, match="cannot draw a int"):
        figures.poincare(3)  # type: ignore[arg-type]


def test_figures_draw_post_api_results() -> None:
    """api.simulate and api.lyapunov results, in memory, through the same functions."""
    from impactchain import api

    if not api.extension_available():
        pytest.skip("the extension impactchain._kernels is not built")
    x0, v0 = api.random_start(6, seed=3, x_amp=0.3, v_amp=1.0)
    sim = api.simulate(6, 1.7, 1.5, x0=x0, v0=v0, transient=50, cycles=40)
    lyap = api.lyapunov(6, 1.7, 1.5, x0=x0, v0=v0, transient=50, cycles=40)
    ax = figures.space_amplitude(sim).axes[0]
    lines = _lines(ax, "strobe-0")
    assert len(lines) == 40
    np.testing.assert_array_equal(lines[-1].get_ydata(), sim.x[-1])
    assert [t.get_text() for t in ax.texts if t.get_gid() == "period"] == [
        period_label(int(p)) for p in sim.periods]
    assert ax.get_ylabel() == "displacement at the section $x_i$ [length]"
    figures.shock_wave(sim, panel_cycles=20)
    figures.poincare(sim, site=2)
    (left,) = _plots(figures.spectrum(lyap))  # no running estimates: the spectrum alone
    (bars,) = left.containers
    np.testing.assert_array_equal(bars.lines[0].get_ydata(), lyap.exponents)
    both = sim.to_run(lyap)
    assert both.lyapunov is not None and both.strobe is not None


# ------------------------------------------------------------------- saved files


def test_saved_png_has_the_resolution_and_the_provenance(make_run: MakeRun,
                                                         tmp_path: Path) -> None:
    from PIL import Image

    runs = [read_run(make_run("red.h5", seed=1)), read_run(make_run("green.h5", seed=4))]
    fig = figures.space_amplitude(runs)
    out = tmp_path / "fig.png"
    fig.savefig(out, dpi=160)  # a figure made here carries its metadata itself
    with Image.open(out) as image:
        assert image.info["dpi"] == pytest.approx((160, 160), abs=0.05)
        assert image.size == (8 * 160, 5 * 160)
        text = dict(image.text)
    assert text["Software"].startswith("impactchain 0.1.0; impactchain.figures ")
    assert text["Source"].splitlines() == [r.path for r in runs]
    assert f"! source: {runs[1].path}\n&chain\n n = 4" in text["Description"]
    assert "seed = 4" in text["Description"] and "seed = 1" in text["Description"]
    assert "&initial kind = 'random', seed = 4" in text["Comment"]  # the resolved namelist
    assert text["Title"].startswith("n = 4, $A$ = 1.7")


def test_save_writes_provenance_into_a_callers_figure(run_file: Path, tmp_path: Path) -> None:
    from PIL import Image

    fig = Figure(figsize=(4, 3))
    figures.poincare(run_file, ax=fig.add_subplot())
    figures.save(fig, tmp_path / "mine.png", dpi=200)
    with Image.open(tmp_path / "mine.png") as image:
        assert image.info["dpi"] == pytest.approx((200, 200), abs=0.05)
        assert image.text["Source"] == str(run_file)
        assert image.text["Software"].startswith("impactchain 0.1.0")


def test_saved_pdf_and_svg_have_the_provenance(run_file: Path, tmp_path: Path) -> None:
    fig = figures.spectrum(read_run(run_file))
    figures.save(fig, tmp_path / "s.pdf")
    pdf = (tmp_path / "s.pdf").read_bytes()
    assert pdf.startswith(b"%PDF-")
    assert b"/Creator (impactchain 0.1.0; impactchain.figures " in pdf
    assert f"/Keywords ({run_file})".encode() in pdf
    assert b"/Subject (! source: " in pdf
    fig.savefig(tmp_path / "s.svg")
    svg = (tmp_path / "s.svg").read_text()
    assert "impactchain 0.1.0" in svg and str(run_file) in svg


def test_a_given_y_range_is_shared_and_what_it_cuts_is_counted(make_run: MakeRun,
                                                               sweep_file: Path) -> None:
    """Figures compared side by side (the gallery's 1a-1d, 2a-2f, 12) take one y range."""
    run = read_run(make_run(n=4, records=10))
    assert run.strobe is not None
    ax = figures.space_amplitude(run, ylim=(-3.0, 3.0)).axes[0]
    assert ax.get_ylim() == (-3.0, 3.0) and "outside" not in ax.get_title()
    cut = figures.space_amplitude(run, ylim=(-0.1, 0.1)).axes[0]
    outside = int(np.count_nonzero(np.abs(run.strobe.x) > 0.1))
    assert f"{outside} of 40 values outside the y range shown" in cut.get_title()
    ky = figures.ky_dimension(read_run(sweep_file), ylim=(0.0, 2.0)).axes[0]
    assert ky.get_ylim() == (0.0, 2.0)
    assert "2 of 7 values outside" in ky.get_title()  # the fixture's 2.5 and 3.0
    with pytest.raises(figures.FigureError, match="lower limit must be below"):
        figures.space_amplitude(run, ylim=(1.0, 1.0))


# ------------------------------------------------------------------- covariant vectors


def _mesh(ax: Axes, gid: str) -> Any:
    (mesh,) = [c for c in ax.collections if c.get_gid() == gid]
    return mesh


def test_clv_space_time_shows_the_stored_weights_and_the_collisions(make_run: MakeRun) -> None:
    # a collision on every bond, a release and a touch (not collisions) on bond 2; the
    # oscillators at 1.0, 1.8, 3.0 and 4.0, the right wall at 5.1
    period = 2 * np.pi / 1.5
    times = (np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7]) + 105) * period
    sites = np.array([0, 1, 2, 3, 4, 2, 2])
    kinds = np.array([0, 0, 1, 0, 0, 2, 3])
    spacing = np.array([1.0, 0.8, 1.2, 1.0, 1.1])
    run = read_run(make_run(n=4, records=30, first_cycle=100, spacing=spacing,
                            events={"time": times, "site": sites, "kind": kinds},
                            clv={"transient": 10, "store": 2}))
    clv = run.clv
    assert clv is not None and clv.site_weight is not None
    fig = figures.clv_space_time(run, vector=[1, 2], start=103, cycles=5)
    left, right = _plots(fig)
    for ax, v in ((left, 1), (right, 2)):
        mesh = _mesh(ax, f"weight-{v}")
        np.testing.assert_array_equal(mesh.get_array(), clv.site_weight[3:8, v - 1, :])
        corners = mesh.get_coordinates()  # (rows + 1, columns + 1, 2)
        np.testing.assert_allclose(corners[0, :, 0], [0.0, 1.4, 2.4, 3.5, 5.1])
        np.testing.assert_allclose(corners[:, 0, 1], np.arange(102.5, 108.0))
        points = np.asarray(_scatter(ax, "collisions").get_offsets())
        # collisions only, at the bond's middle (the walls for bonds 0 and n), at t/T
        np.testing.assert_allclose(points, [[0.0, 105.1], [1.4, 105.2], [2.4, 105.3],
                                            [3.5, 105.4], [5.1, 105.5]])
        assert ax.get_ylim() == pytest.approx((102.5, 107.5))
        assert _walls(ax) == pytest.approx([0.0, 5.1])
        assert mesh.get_clim() == (0.0, float(clv.site_weight[3:8].max()))
    # vector 1 lives on the left half, vector 2 on the right (the fixture's design)
    assert _mesh(left, "weight-1").get_array()[:, 2:].max() == 0.0
    assert _mesh(right, "weight-2").get_array()[:, :2].max() == 0.0
    (cax,) = _colorbars(fig)
    assert cax.get_ylabel() == "weight of the oscillator $w_i$ [1]"
    assert "$\\lambda_{1}$ = 0.410 $\\pm$ 0.030" in left.get_title()  # /clv's, not /lyapunov's


def test_clv_space_time_section_phase_records_and_errors(make_run: MakeRun) -> None:
    run = read_run(make_run(n=4, records=30, first_cycle=0, phase=np.pi, events=False,
                            clv={"transient": 10, "store": 2}))
    fig = figures.clv_space_time(run)
    (ax,) = _plots(fig)
    assert ax.get_ylim() == pytest.approx((0.0, 20.0))  # records 0..19 at c + 1/2
    assert not [c for c in ax.collections if c.get_gid() == "collisions"]
    assert "no events recorded" in fig.get_suptitle()
    with pytest.raises(figures.FigureError, match=r"vector 3 is outside 1..2"):
        figures.clv_space_time(run, vector=3)
    with pytest.raises(figures.FigureError, match="start cycle 25 is outside the records "
                                                  "with vectors 0..19"):
        figures.clv_space_time(run, start=25)
    bare = make_run("bare.h5", clv={"store": 0})
    with pytest.raises(SchemaError, match="no /clv/site_weight, needed by clv-space-time"):
        figures.clv_space_time(bare)
    with pytest.raises(figures.FigureError, match="no /clv/site_weight"):
        figures.clv_space_time(read_run(bare))
    with pytest.raises(figures.FigureError, match="no covariant Lyapunov vectors"):
        figures.clv_space_time(read_run(make_run("plain.h5")))


def test_clv_ipr_shows_the_mean_ipr_and_the_vectors_exponents(make_run: MakeRun) -> None:
    run = read_run(make_run(n=4, records=30, lyapunov=True,
                            clv={"store": 3, "unstable": 2}))
    clv = run.clv
    assert clv is not None
    upper, lower = _plots(figures.clv_ipr(run))
    (mean,) = _lines(upper, "ipr-mean")
    np.testing.assert_array_equal(mean.get_xdata(), np.arange(1, 9))
    np.testing.assert_allclose(mean.get_ydata(), clv.ipr.mean(axis=0))
    (even,) = _lines(upper, "ipr-even")
    assert even.get_ydata()[0] == pytest.approx(0.25)
    band = [c for c in upper.collections if c.get_gid() == "ipr-quartiles"]
    assert len(band) == 1
    ys = np.concatenate([b.lines[0].get_ydata() for b in lower.containers])
    np.testing.assert_array_equal(ys, clv.exponents)  # /clv/exponents, not /lyapunov's
    filled = [b for b in lower.containers if b.lines[0].get_gid() == "exponents-unstable"]
    (unstable,) = filled
    assert unstable.lines[0].get_xdata().tolist() == [1, 2]
    spans = [seg[1, 1] - seg[0, 1] for b in lower.containers
             for seg in b.lines[2][0].get_segments()]
    np.testing.assert_allclose(spans, 2 * clv.stderr)
    assert lower.get_xlabel() == "covariant vector index $j$ [1]"
    assert upper.get_ylabel() == "inverse participation ratio $\\mathrm{IPR}$ [1]"


def test_clv_angles_histogram_counts_every_record(make_run: MakeRun) -> None:
    path = make_run(n=4, records=60, clv={"transient": 10})
    with h5py.File(path, "r+") as f:
        angle = f["clv/min_angle"][:]
        angle[[3, 7]] = np.nan
        f["clv/min_angle"][...] = angle
    run = read_run(path)
    ax = figures.clv_angles(run, bins=12).axes[0]
    bars = list(ax.patches)
    heights = np.array([p.get_height() for p in bars])
    assert len(bars) == 12 and heights.sum() == 48
    lefts = np.array([p.get_x() for p in bars])
    ratios = lefts[1:] / lefts[:-1]
    np.testing.assert_allclose(ratios, ratios[0])  # log-spaced
    assert lefts[0] <= np.nanmin(angle) and lefts[-1] + bars[-1].get_width() == \
        pytest.approx(np.pi / 2)
    assert ax.get_xscale() == "log"
    finite = angle[np.isfinite(angle)]
    below = int(np.count_nonzero(finite < 0.1))
    assert f"{below} of 48 records ({below / 48:.1%}) below 0.1 rad" in ax.get_title()
    assert "2 records without an angle" in ax.get_title()
    (near,) = _lines(ax, "near")
    assert near.get_xdata()[0] == 0.1
    wider = figures.clv_angles(run, near=0.3).axes[0]
    wide = int(np.count_nonzero(finite < 0.3))
    assert f"{wide} of 48 records ({wide / 48:.1%}) below 0.3 rad" in wider.get_title()
    with h5py.File(path, "r+") as f:
        f["clv/min_angle"][...] = np.nan
    with pytest.raises(figures.FigureError, match="holds no angle"):
        figures.clv_angles(read_run(path))


def test_clv_figures_label_units_and_draw_into_given_axes(make_run: MakeRun) -> None:
    run = read_run(make_run(n=4, records=30, clv=True))
    made = [figures.clv_space_time(run, vector=[1, 2]), figures.clv_ipr(run),
            figures.clv_angles(run)]
    for fig in made:
        for label in _all_labels(fig):
            assert re.fullmatch(r"[^\[\]]+ \[[^\[\]]+\]", label), label
    fig = Figure()
    axes = list(fig.subplots(1, 5))
    assert figures.clv_space_time(run, vector=[1, 2], ax=axes[:2]) is fig
    assert figures.clv_ipr(run, ax=axes[2:4]) is fig
    assert figures.clv_angles(run, ax=axes[4]) is fig
    assert set(_plots(fig)) == set(axes) and fig.get_suptitle() == ""
    assert all(ax.has_data() for ax in axes)
    alone = Figure()
    (ax,) = _plots(figures.clv_ipr(run, ax=alone.add_subplot()))
    assert _lines(ax, "ipr-mean") and ax.get_xlabel() == "covariant vector index $j$ [1]"
    with pytest.raises(figures.FigureError, match="draws into 2 axes, 1 given"):
        figures.clv_space_time(run, vector=[1, 2], ax=Figure().add_subplot())


# ------------------------------------------------------------------ what fits the figure


def _unreadable(fig: Figure) -> list[str]:
    """What a reader cannot read, measured with the Agg renderer as a PNG is drawn: text
    reaching beyond the figure's edges, and tick labels of one axis that touch or overlap
    (only the ticks inside the axis' view are drawn)."""
    FigureCanvasAgg(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    edge = fig.bbox
    found = []
    ticks: list[Text] = []
    for ax in fig.axes:
        for axis, i in ((ax.xaxis, 0), (ax.yaxis, 1)):
            low, high = sorted(axis.get_view_interval())
            slack = 1e-9 * (high - low)
            drawn = [t for t in axis.get_ticklabels() if t.get_visible() and t.get_text()
                     and low - slack <= t.get_position()[i] <= high + slack]
            ticks += axis.get_ticklabels()
            boxes = sorted((t.get_window_extent(renderer) for t in drawn),
                           key=(lambda b: b.x0) if i == 0 else (lambda b: b.y0))
            for a, b in zip(boxes, boxes[1:]):
                apart = b.x0 - a.x1 if i == 0 else b.y0 - a.y1
                if apart <= 0:
                    found.append(f"{ax.get_label() or 'axes'}: tick labels {apart:.1f} px apart")
            for t in drawn:
                box = t.get_window_extent(renderer)
                if box.x0 < edge.x0 or box.x1 > edge.x1 or box.y0 < edge.y0 or box.y1 > edge.y1:
                    found.append(f"tick label {t.get_text()!r} beyond the figure")
    for t in fig.findobj(Text):
        if t in ticks or not t.get_visible() or not t.get_text():
            continue
        box = t.get_window_extent(renderer)
        if (box.x0 < edge.x0 - 0.5 or box.x1 > edge.x1 + 0.5 or box.y0 < edge.y0 - 0.5
                or box.y1 > edge.y1 + 0.5):
            found.append(f"{t.get_text()!r} reaches {box.x0:.0f}..{box.x1:.0f} px of "
                         f"0..{edge.x1:.0f}")
    return found


LONG_END_REASON = ("branch 0 (period 1): grazing at amplitude = 1.8141825: the impacts change "
                   "there, the branch ends\nbranch 1 (period 2): Newton failed on the doubled "
                   "orbit at amplitude = 2.4355114: no decrease of the residual along the "
                   "Newton step (halved 12 times)")


@pytest.mark.parametrize("draw", ["branches", "multipliers"])
def test_continuation_titles_fit_the_figure(tmp_path: Path, draw: str) -> None:
    """Issue 32, 8: a continuation's end reasons, one a branch, are long; the title that
    quotes them is wrapped to the figure instead of running off both edges."""
    path = write_continuation(tmp_path / "cont.h5")
    with h5py.File(path, "r+") as f:
        f["continuation"].attrs["end_reason"] = LONG_END_REASON
    fig = getattr(figures, draw)(read_run(path))
    assert _unreadable(fig) == []
    assert "the branch ends" in fig.axes[0].get_title()  # wrapped when drawn, not cut


def test_poincare_tick_labels_stand_apart(make_run: MakeRun) -> None:
    """Figure 8's section: x from -0.91 to -0.72 took ticks every 0.025 whose labels
    (-0.900, -0.875, ...) ran together; fewer ticks, each label readable."""
    path = make_run("section.h5", n=16, records=50)
    with h5py.File(path, "r+") as f:
        x, v = f["strobe/x"][...], f["strobe/v"][...]
        x[:, 0] = np.linspace(-0.91, -0.7245, x.shape[0])
        v[:, 0] = np.linspace(-2.137, -2.046, v.shape[0])
        f["strobe/x"][...], f["strobe/v"][...] = x, v
    fig = figures.poincare(read_run(path), site=1)
    assert _unreadable(fig) == []
    (ax,) = _plots(fig)
    low, high = ax.get_xlim()
    assert len([t for t in ax.get_xticks() if low <= t <= high]) >= 3
