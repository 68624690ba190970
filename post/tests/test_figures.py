"""post.figures: the axes hold the data they claim to show."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection, PathCollection
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from post import figures
from post.io import Run, read_run
from post.shockwave import build_shock_waves

MakeRun = Callable[..., Path]


def _lines(ax: Axes, gid_prefix: str) -> list[Line2D]:
    return [line for line in ax.get_lines() if (line.get_gid() or "").startswith(gid_prefix)]


def _walls(ax: Axes) -> list[float]:
    return sorted(float(line.get_xdata()[0]) for line in _lines(ax, "wall"))


def _scatter(ax: Axes, gid: str) -> PathCollection:
    (points,) = [c for c in ax.collections if isinstance(c, PathCollection) and c.get_gid() == gid]
    return points


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
    assert legend is not None and [t.get_text() for t in legend.get_texts()] == ["a", "b"]


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
    (ax,) = figures.lyapunov([run], k=4).axes
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
    top, bottom = figures.lyapunov([run], k=20, with_bifurcation=True).axes
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


# ---------------------------------------------------------------------------- spectrum


def test_spectrum_shows_exponents_with_error_bars(run_file: Path) -> None:
    run = read_run(run_file)
    left, right = figures.spectrum(run).axes
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
    running = _lines(figures.spectrum(run).axes[1], "running-")
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
