"""Finite-time Lyapunov exponents (docs/model.md section 7.10) and the blocking standard
error's block length (section 7.4): impactchain.io reads /finite_time into
:class:`FiniteTime` and /lyapunov/stderr_block into ``Lyapunov.stderr_block``, the figure
`finite_time` and its command draw their histograms; and the same with a small run by the
simulator (skipped when it cannot be built).

``write_finite_time`` writes the layout the simulator writes: a version-2 run with
/lyapunov (and its ``stderr_block``), and /finite_time with the dimension scales ``cycle``
(the drive cycle at each window's end) and ``exponent`` (1..k) attached to ``exponents``, and
the attribute ``window``. So that a figure computing what the file stores would be caught,
the windows' mean is not the stored exponent.
"""

from __future__ import annotations

import math
import os
import re
import subprocess
import sys
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from matplotlib.colors import to_rgba
from matplotlib.patches import Polygon

from conftest import lyapunov_spectrum, write_run
from impactchain import figures
from impactchain.cli import main
from impactchain.io import FILE_UNITS, FiniteTime, SchemaError, read_run

DATA = Path(__file__).resolve().parent / "data"

N = 2
"""Oscillators of the synthetic run: k = 2n = 4 exponents."""
K = 2 * N
FIRST = 100
"""The synthetic run's first record: its window w ends at drive cycle FIRST + (w + 1) W - 1."""
STDERR = 0.02
"""The synthetic /lyapunov/stderr (conftest), bits per cycle."""
BLOCKS = (64, 32, 32, 128)
"""The synthetic /lyapunov/stderr_block, drive cycles."""


def window_exponents(windows: int, window: int, seed: int = 3) -> np.ndarray:
    """(windows, K): the stored spectrum plus a spread that narrows as 1/sqrt(window), and an
    offset of 0.05, so that the windows' mean is not the stored exponent."""
    rng = np.random.default_rng(seed)
    spread = rng.standard_normal((windows, K)) / math.sqrt(window)
    return lyapunov_spectrum(N)[None, :] + 0.05 + spread


def write_finite_time(
    path: str | Path,
    windows: int = 40,
    window: int = 100,
    *,
    exponents: np.ndarray | None = None,
    seed: int | None = None,
    stderr_block: bool = True,
    lyapunov: bool = True,
    finite_time: bool = True,
    transposed: bool = False,
    leave_out_attrs: Sequence[str] = (),
) -> Path:
    """Write a synthetic run with finite-time exponents and return its path.

    ``exponents``: (windows, K) to store (default :func:`window_exponents`); ``seed``: the
    run's random start (what :func:`impactchain.figures.run_labels` tells runs apart by);
    ``stderr_block``: False for a /lyapunov of before the blocking plateau; ``lyapunov``:
    False for a run stopped early (the end of a run writes /lyapunov); ``transposed``: the
    exponents in Fortran's order (exponent, window), which the reader must refuse.
    """
    data = window_exponents(windows, window) if exponents is None else np.asarray(exponents)
    path = write_run(path, n=N, records=windows * window, strobe=False, events=False,
                     lyapunov=lyapunov, schema_version=2, seed=seed, first_cycle=FIRST,
                     complete=int(lyapunov))
    with h5py.File(path, "r+") as f:
        if lyapunov and stderr_block:
            f["lyapunov/stderr_block"] = np.asarray(BLOCKS, dtype=np.int64)
            f["lyapunov/stderr_block"].attrs.update(
                long_name="drive cycles per block at which stderr was read", units="1",
                model_units="drive cycles")
        if not finite_time:
            return path
        g = f.create_group("finite_time")
        attrs = {"window": np.int32(window)}
        for name, value in attrs.items():
            if name not in leave_out_attrs:
                g.attrs[name] = value
        g["cycle"] = FIRST - 1 + window * np.arange(1, data.shape[0] + 1, dtype=np.int64)
        g["cycle"].attrs.update(long_name="drive cycle at the end of the window", units="1",
                                model_units="drive cycles")
        g["cycle"].make_scale("cycle")
        g["exponent"] = np.arange(1, data.shape[1] + 1, dtype=np.int32)
        g["exponent"].attrs.update(long_name="exponent index", units="1")
        g["exponent"].make_scale("exponent")
        g["exponents"] = data.T if transposed else data
        g["exponents"].attrs.update(long_name="finite-time Lyapunov exponent", units="1",
                                    model_units="bits per drive cycle")
        if not transposed:
            g["exponents"].dims[0].attach_scale(g["cycle"])
            g["exponents"].dims[1].attach_scale(g["exponent"])
    return path


MakeFiniteTime = Callable[..., Path]


@pytest.fixture
def make_ft(tmp_path: Path) -> MakeFiniteTime:
    """``make_ft(name, **kw)`` writes ``tmp_path/name`` with :func:`write_finite_time`."""

    def make(name: str = "ft.h5", **kwargs: Any) -> Path:
        return write_finite_time(tmp_path / name, **kwargs)

    return make


def sd_of_mean(values: np.ndarray) -> float:
    """``sd / sqrt(N)`` of the windows' exponents."""
    return float(np.std(values, ddof=1)) / math.sqrt(values.size)


# ---------------------------------------------------------------------------------- reading


def test_reads_the_windows_as_stored(make_ft: MakeFiniteTime) -> None:
    path = make_ft(windows=40, window=100)
    run = read_run(path)
    ft = run.finite_time
    assert isinstance(ft, FiniteTime)
    assert (ft.window, ft.n_windows, ft.k) == (100, 40, K)
    assert ft.cycle.shape == (40,) and ft.exponents.shape == (40, K)
    assert ft.cycle.dtype == np.int64 and ft.exponents.dtype == np.float64
    with h5py.File(path) as f:
        np.testing.assert_array_equal(ft.exponents, f["finite_time/exponents"][()])
        np.testing.assert_array_equal(ft.cycle, f["finite_time/cycle"][()])
        assert ft.window == f["finite_time"].attrs["window"]
    assert ft.cycle[0] == FIRST + 99 and (np.diff(ft.cycle) == 100).all()
    assert not ft.exponents.flags.writeable and not ft.cycle.flags.writeable
    assert run.unit("finite_time/exponents") == "bits per drive cycle"
    assert run.unit("finite_time/cycle") == "drive cycles"


def test_reads_the_block_length_of_the_standard_error(make_ft: MakeFiniteTime) -> None:
    path = make_ft()
    lyap = read_run(path).lyapunov
    assert lyap is not None and lyap.stderr_block is not None
    with h5py.File(path) as f:
        np.testing.assert_array_equal(lyap.stderr_block, f["lyapunov/stderr_block"][()])
    assert lyap.stderr_block.dtype == np.int64 and lyap.stderr_block.shape == (K,)
    assert read_run(path).unit("lyapunov/stderr_block") == "drive cycles"


def test_units_of_the_new_datasets() -> None:
    assert FILE_UNITS["finite_time/exponents"] == "bits per drive cycle"
    assert FILE_UNITS["finite_time/cycle"] == "drive cycles"
    assert FILE_UNITS["lyapunov/stderr_block"] == "drive cycles"


@pytest.mark.parametrize("name", ["v1_run.h5", "v2_run.h5"])
def test_older_files_have_neither(name: str) -> None:
    """The simulator's files of before /finite_time and /lyapunov/stderr_block."""
    run = read_run(DATA / name)
    assert run.finite_time is None
    assert run.lyapunov is not None and run.lyapunov.stderr_block is None
    assert run.lyapunov.stderr.shape == run.lyapunov.exponents.shape


def test_a_file_without_the_group(make_ft: MakeFiniteTime) -> None:
    path = make_ft(finite_time=False, stderr_block=False)
    run = read_run(path)
    assert run.finite_time is None
    assert run.lyapunov is not None and run.lyapunov.stderr_block is None
    with pytest.raises(SchemaError, match=r"no /finite_time, needed by finite-time \(the run "
                                          r"computed no finite-time Lyapunov exponents: "
                                          r"&lyapunov window = 0\)"):
        read_run(path, require=("finite_time",), purpose="finite-time")


def test_finite_time_only_when_asked(make_ft: MakeFiniteTime) -> None:
    path = make_ft()
    assert read_run(path, groups=("lyapunov",)).finite_time is None
    assert read_run(path, groups=("finite_time",)).finite_time is not None


def test_bad_layouts_are_refused(make_ft: MakeFiniteTime) -> None:
    with pytest.raises(SchemaError, match="axes transposed"):
        read_run(make_ft("t.h5", transposed=True))
    with pytest.raises(SchemaError, match="/finite_time lacks attribute 'window'"):
        read_run(make_ft("a.h5", leave_out_attrs=("window",)))
    path = make_ft("w.h5")
    with h5py.File(path, "r+") as f:
        f["finite_time"].attrs["window"] = np.int32(0)
    with pytest.raises(SchemaError, match=r"/finite_time@window = 0 must be >= 1"):
        read_run(path)
    path = make_ft("c.h5")
    with h5py.File(path, "r+") as f:
        del f["finite_time/cycle"]
        f["finite_time/cycle"] = np.arange(3, dtype=np.int64)
    with pytest.raises(SchemaError, match=r"/finite_time/exponents has shape \(40, 4\), "
                                          r"expected \(3, \*\)"):
        read_run(path)


# ---------------------------------------------------------------------------------- figures


def histograms(ax: Axes) -> list[Polygon]:
    return [p for p in ax.patches if (p.get_gid() or "").startswith("histogram-")]


def of_gid(ax: Axes, gid: str) -> Any:
    found = [a for a in (*ax.lines, *ax.patches) if a.get_gid() == gid]
    assert len(found) == 1, (gid, found)
    return found[0]


def legend_texts(ax: Axes) -> list[str]:
    legend = ax.get_legend()
    assert legend is not None
    return [t.get_text() for t in legend.get_texts()]


def steps(patch: Polygon) -> tuple[np.ndarray, np.ndarray]:
    """The bin edges and the heights of a ``stepfilled`` histogram's outline."""
    xy = np.asarray(patch.get_xy())
    top = xy[1:-1]  # from (edge 0, 0) up and along the tops to (last edge, 0)
    edges = np.unique(top[:, 0])
    heights = top[1::2, 1][: edges.size - 1]
    return edges, heights


def test_one_file_draws_the_density_the_line_and_the_band(make_ft: MakeFiniteTime) -> None:
    path = make_ft()
    run = read_run(path)
    assert run.finite_time is not None and run.lyapunov is not None
    values = run.finite_time.exponents[:, 0]
    fig = figures.finite_time(path)
    assert isinstance(fig, Figure)
    (ax,) = [a for a in fig.axes if a.has_data()]
    (hist,) = histograms(ax)
    edges, heights = steps(hist)
    want, want_edges = np.histogram(values, bins=np.histogram_bin_edges(values, "auto"),
                                    density=True)
    np.testing.assert_allclose(edges, want_edges)
    np.testing.assert_allclose(heights, want)
    assert float(np.sum(heights * np.diff(edges))) == pytest.approx(1.0)
    # the stored exponent and its stored error, not the windows' mean and spread
    mean = float(run.lyapunov.exponents[0])
    assert abs(float(values.mean()) - mean) > 0.04
    line = of_gid(ax, "exponent-1")
    assert list(line.get_xdata()) == [mean, mean] and line.get_linestyle() == "--"
    corners = of_gid(ax, "stderr-1").get_path().transformed(
        of_gid(ax, "stderr-1").get_patch_transform()).vertices
    low, high = float(corners[:, 0].min()), float(corners[:, 0].max())
    assert (low, high) == pytest.approx((mean - STDERR, mean + STDERR))
    (entry,) = legend_texts(ax)
    first, second = entry.split("\n")
    assert first == f"$\\lambda_{{1}}$ = {mean:.4g} $\\pm$ {STDERR:.3g}"
    assert second == (f"W = 100 cycles, 40 windows, sd/$\\sqrt{{N}}$ = "
                      f"{sd_of_mean(values):.3g} vs stderr = {STDERR:.3g} (blocks of "
                      f"{BLOCKS[0]} cycles)")
    for label in (ax.get_xlabel(), ax.get_ylabel()):
        assert re.fullmatch(r"[^\[\]]+ \[[^\[\]]+\]", label), label
    assert ax.get_xlabel() == "finite-time exponent $\\lambda_{1}$ [bits per drive cycle]"
    assert ax.get_ylabel() == "probability density [1/(bits per drive cycle)]"
    assert "windows of W cycles" in fig.get_suptitle()


def test_two_files_overlay_by_window(make_ft: MakeFiniteTime) -> None:
    short = make_ft("w10.h5", windows=400, window=10)
    long = make_ft("w100.h5", windows=40, window=100)
    fig = figures.finite_time([short, long])
    (ax,) = [a for a in fig.axes if a.has_data()]
    first, second = histograms(ax)
    assert first.get_edgecolor() != second.get_edgecolor()
    for i, hist in enumerate((first, second), start=1):
        assert to_rgba(of_gid(ax, f"exponent-{i}").get_color()) == hist.get_edgecolor()
    # the narrowing: the long windows' histogram spans less
    assert np.ptp(steps(second)[0]) < 0.5 * np.ptp(steps(first)[0])
    entries = legend_texts(ax)
    assert [e.split("\n")[1].split(",")[0] for e in entries] == ["W = 10 cycles",
                                                                 "W = 100 cycles"]
    assert "400 windows" in entries[0] and "40 windows" in entries[1]
    # only the window differs: no other label before the exponent
    assert all(e.startswith("$\\lambda_{1}$") for e in entries)
    handles = ax.get_legend().legend_handles
    assert [h.get_edgecolor() for h in handles] == [first.get_edgecolor(),
                                                    second.get_edgecolor()]


def test_runs_that_differ_otherwise_are_labelled(make_ft: MakeFiniteTime) -> None:
    runs = [make_ft("a.h5", seed=1), make_ft("b.h5", seed=2)]
    fig = figures.finite_time(runs)
    (ax,) = [a for a in fig.axes if a.has_data()]
    assert [e.split(":")[0] for e in legend_texts(ax)] == ["seed 1", "seed 2"]
    fig = figures.finite_time(runs, labels=["from rest", "kicked"])
    (ax,) = [a for a in fig.axes if a.has_data()]
    assert [e.split(":")[0] for e in legend_texts(ax)] == ["from rest", "kicked"]
    with pytest.raises(figures.FigureError, match="1 labels for 2 runs"):
        figures.finite_time(runs, labels=["one"])


def test_chosen_exponents_get_a_panel_each(make_ft: MakeFiniteTime) -> None:
    path = make_ft()
    run = read_run(path)
    assert run.finite_time is not None
    fig = figures.finite_time(run, exponents=[1, 3], bins=6)
    axes = [a for a in fig.axes if a.has_data()]
    assert len(axes) == 2
    for ax, j in zip(axes, (1, 3)):
        (hist,) = histograms(ax)
        edges, heights = steps(hist)
        values = run.finite_time.exponents[:, j - 1]
        np.testing.assert_allclose(edges, np.histogram_bin_edges(values, 6))
        assert heights.size == 6
        assert ax.get_xlabel().startswith(f"finite-time exponent $\\lambda_{{{j}}}$")
        assert legend_texts(ax)[0].startswith(f"$\\lambda_{{{j}}}$")
        assert f"(blocks of {BLOCKS[j - 1]} cycles)" in legend_texts(ax)[0]
    assert axes[0].get_ylim() == axes[1].get_ylim()


def test_collapsed_windows_are_counted_not_drawn(make_ft: MakeFiniteTime) -> None:
    data = window_exponents(40, 100)
    data[30:, 3] = -np.inf
    data[:, 2] = -np.inf
    path = make_ft(exponents=data)
    fig = figures.finite_time(path, exponents=4)
    (ax,) = [a for a in fig.axes if a.has_data()]
    (hist,) = histograms(ax)
    edges, _ = steps(hist)
    np.testing.assert_allclose(edges[[0, -1]], [data[:30, 3].min(), data[:30, 3].max()])
    assert f"30 windows (+10 at $-\\infty$), sd/$\\sqrt{{N}}$ = {sd_of_mean(data[:30, 3]):.3g}" \
        in legend_texts(ax)[0]
    with pytest.raises(figures.FigureError, match="exponent 3 is -infinity in every window"):
        figures.finite_time(path, exponents=3)


def test_a_run_without_lyapunov_or_block_lengths(make_ft: MakeFiniteTime) -> None:
    stopped = make_ft("stopped.h5", lyapunov=False)
    fig = figures.finite_time(stopped)
    (ax,) = [a for a in fig.axes if a.has_data()]
    assert not [line for line in ax.lines if line.get_gid() == "exponent-1"]
    (entry,) = legend_texts(ax)
    assert entry.startswith("no /lyapunov in this run\nW = 100 cycles, 40 windows")
    assert "stderr" not in entry
    assert "(interrupted run)" in fig.get_suptitle()
    older = make_ft("older.h5", stderr_block=False)
    (entry,) = legend_texts([a for a in figures.finite_time(older).axes if a.has_data()][0])
    assert entry.endswith(f"vs stderr = {STDERR:.3g}") and "blocks" not in entry


def test_files_without_finite_time_are_refused(make_ft: MakeFiniteTime) -> None:
    bare = make_ft("bare.h5", finite_time=False)
    with pytest.raises(SchemaError, match="no /finite_time, needed by finite-time"):
        figures.finite_time(bare)
    with pytest.raises(SchemaError, match=r"bare\.h5: no /finite_time"):
        figures.finite_time([make_ft("ok.h5"), bare])
    with pytest.raises(figures.FigureError, match=r"no /finite_time \(the run computed no "
                                                  r"finite-time Lyapunov exponents"):
        figures.finite_time(read_run(bare))
    with pytest.raises(figures.FigureError, match=r"exponent 5 is outside 1\.\.4"):
        figures.finite_time(make_ft(), exponents=[1, 5])
    with pytest.raises(figures.FigureError, match="bins = 0 must be >= 1"):
        figures.finite_time(make_ft(), bins=0)


def test_draws_into_given_axes(make_ft: MakeFiniteTime) -> None:
    fig = Figure()
    left, right = fig.subplots(1, 2)
    assert figures.finite_time(make_ft(), exponents=[2, 4], ax=[left, right]) is fig
    assert histograms(left) and histograms(right)
    assert fig.get_suptitle() == ""
    with pytest.raises(figures.FigureError, match="draws into 2 axes, 1 given"):
        figures.finite_time(make_ft(), exponents=[2, 4], ax=left)


# -------------------------------------------------------------------------------------- cli


def error_line(capsys: pytest.CaptureFixture[str]) -> str:
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("impactchain: error: "), lines
    return lines[0]


def test_cli_command(make_ft: MakeFiniteTime, tmp_path: Path,
                     capsys: pytest.CaptureFixture[str]) -> None:
    short, long = make_ft("w10.h5", windows=400, window=10), make_ft("w100.h5")
    out = tmp_path / "one.png"
    assert main(["finite-time", str(long), "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert main(["finite-time", str(short), str(long), "--exponents", "1,2", "--bins", "9",
                 "-o", str(tmp_path / "two.pdf")]) == 0
    assert (tmp_path / "two.pdf").stat().st_size > 0
    bare = make_ft("bare.h5", finite_time=False)
    assert main(["finite-time", str(long), str(bare), "-o", str(tmp_path / "bad.png")]) == 2
    assert "bare.h5: no /finite_time, needed by finite-time" in error_line(capsys)
    assert not (tmp_path / "bad.png").exists()
    assert main(["finite-time", str(long), "--exponents", "7", "-o",
                 str(tmp_path / "bad.png")]) == 2
    assert "exponent 7 is outside 1..4" in error_line(capsys)
    for bad in ("0", "one"):
        with pytest.raises(SystemExit) as exit_:
            main(["finite-time", str(long), "--exponents", bad, "-o", str(tmp_path / "x.png")])
        assert exit_.value.code == 2
    assert "--exponents" in capsys.readouterr().err
    assert main(["all", str(long), "-o", str(tmp_path / "all")]) == 0
    assert str(tmp_path / "all_finite_time.png") in capsys.readouterr().out.split()
    assert main(["all", str(bare), "-o", str(tmp_path / "b")]) == 0
    assert not (tmp_path / "b_finite_time.png").exists()


def test_cli_as_a_module(make_ft: MakeFiniteTime, tmp_path: Path) -> None:
    def run(*args: str | Path) -> subprocess.CompletedProcess[str]:
        return subprocess.run([sys.executable, "-m", "impactchain", *map(str, args)],
                              capture_output=True, text=True, timeout=120, check=False,
                              env={**os.environ, "MPLBACKEND": "Agg"})

    result = run("finite-time", make_ft(), "-o", tmp_path / "m.png")
    assert result.returncode == 0, result.stderr
    result = run("finite-time", make_ft("bare.h5", finite_time=False), "-o", tmp_path / "n.png")
    assert result.returncode == 2
    (line,) = result.stderr.strip().splitlines()
    assert line.startswith("impactchain: error: ") and "no /finite_time" in line
    assert not (tmp_path / "n.png").exists()


# ------------------------------------------------------------------ a run by the simulator


def test_a_run_by_the_simulator(simulator: Path, tmp_path: Path) -> None:
    (tmp_path / "w.nml").write_text(
        "&chain n = 8, spacing = 1.0, damping = 0.05, restitution = 0.7, amplitude = 1.7, "
        "omega = 1.5, boundary = 'fixed' /\n"
        "&initial kind = 'random', seed = 1, x_amp = 0.3, v_amp = 0.3 /\n"
        "&run transient = 200, cycles = 2000, record_events = .false. /\n"
        "&lyapunov vectors = 3, window = 50 /\n&output file = 'w.h5' /\n")
    result = subprocess.run([str(simulator), "--quiet", "w.nml"], cwd=tmp_path,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    path = tmp_path / "w.h5"
    run = read_run(path)
    ft, lyap = run.finite_time, run.lyapunov
    assert ft is not None and lyap is not None and lyap.stderr_block is not None
    assert (ft.window, ft.n_windows, ft.k) == (50, 40, 3)
    with h5py.File(path) as f:
        np.testing.assert_array_equal(ft.exponents, f["finite_time/exponents"][()])
        np.testing.assert_array_equal(ft.cycle, f["finite_time/cycle"][()])
        np.testing.assert_array_equal(lyap.stderr_block, f["lyapunov/stderr_block"][()])
    np.testing.assert_array_equal(ft.cycle, 200 + 50 * np.arange(1, 41))
    # W divides the recorded cycles: the windows' mean is the exponent (section 7.10)
    np.testing.assert_allclose(np.sort(ft.exponents.mean(axis=0))[::-1], lyap.exponents,
                               rtol=0, atol=1e-12)
    assert (lyap.stderr_block >= 1).all()
    assert run.unit("finite_time/exponents") == "bits per drive cycle"
    fig = figures.finite_time(run, exponents=[1, 2])
    assert [len(histograms(ax)) for ax in fig.axes if ax.has_data()] == [1, 1]
