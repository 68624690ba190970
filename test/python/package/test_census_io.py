"""Census files (attractors and their basin fractions, docs/model.md section 13):
impactchain.io reads /census into :class:`Census`, xarray opens it with its dimensions, the
figures `basin_fractions`, `basin_plane` and `ensemble_spectra` and their commands draw it;
an older file without the samples' exponents gets them from lambda1; and the same with small
censuses run by the simulator (skipped when it cannot be built).

``write_census`` writes the layout the simulator writes: the root and /params of a version-2
file (without the swept parameter along a sweep), and /census with the dimension scales
point, sample (1..N), oscillator (1..n), attractor (0..A-1), bond (0..n) and exponent (1..k)
attached to every dataset, each with ``long_name``, ``units`` and (for the reduced units)
``model_units``.
"""

from __future__ import annotations

import math
import subprocess
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

import h5py
import numpy as np
import pytest
from matplotlib.axes import Axes
from matplotlib.collections import LineCollection
from matplotlib.container import BarContainer, ErrorbarContainer
from matplotlib.figure import Figure
from matplotlib.image import AxesImage

from conftest import write_run
from impactchain import figures
from impactchain.cli import main
from impactchain.io import (ATTRACTOR_KINDS, Census, SchemaError, period_pattern, read_census,
                            read_run)

N = 4
"""Oscillators of the synthetic census."""

# Two points (A = 2.2, 2.3) of 10 samples; attractors 0-2 found at point 0, 3-4 at point 1.
VALUES = (2.2, 2.3)
KINDS = ("periodic", "periodic", "chaotic", "periodic", "aperiodic-nonchaotic")
PERIODS = ((1, 1, 1, 1), (2, 2, 1, 1), (0, 0, 0, 0), (1, 1, 1, 1), (0, 0, 0, 0))
POINT = (0, 0, 0, 1, 1)
IDS = ((0, 1, 0, 2, 0, 1, 0, 0, 2, 0), (3, 3, 4, 3, 3, 3, 3, 4, 3, 3))
MIRRORED = ((0, 1, 0, 0, 1, 0, 0, 0, 0, 0), (0, 0, 0, 0, 0, 0, 0, 1, 0, 0))
K = 3
"""Exponents per sample of the synthetic census."""


def fractions(ids: Sequence[Sequence[int]], attractors: int) -> np.ndarray:
    """(P, A): the fraction of each point's samples on each attractor."""
    ids = np.asarray(ids)
    return np.array([np.bincount(row, minlength=attractors)[:attractors] / row.size for row in ids])


def sample_spectra(ids: np.ndarray, k: int) -> np.ndarray:
    """(P, N, k) descending spectra, the first lambda1 (0.3 on attractor 2, else -0.05), the
    others below it by j/2 and a sample-dependent amount."""
    lambda1 = np.where(ids == 2, 0.3, -0.05)
    points, samples = ids.shape
    shift = 0.01 * np.arange(samples)[np.newaxis, :, np.newaxis] * np.arange(k)
    return lambda1[:, :, np.newaxis] - 0.5 * np.arange(k) - shift * (1 + np.arange(points))[
        :, np.newaxis, np.newaxis]


def ensembles(spectra: np.ndarray, ids: np.ndarray, point: Sequence[int],
              a: int) -> tuple[np.ndarray, np.ndarray]:
    """(A, k) each attractor's mean spectrum and the standard deviation (n - 1) between its
    samples', by numpy (zeros for an attractor without samples)."""
    k = spectra.shape[2]
    mean, spread = np.zeros((a, k)), np.zeros((a, k))
    for j, p in enumerate(point[:a]):
        members = spectra[min(p, len(ids) - 1)][ids[min(p, len(ids) - 1)] == j]
        if members.shape[0]:
            mean[j] = members.mean(axis=0)
        if members.shape[0] > 1:
            spread[j] = members.std(axis=0, ddof=1)
    return mean, spread


def write_census(
    path: str | Path,
    values: Sequence[float] | None = VALUES,
    ids: Sequence[Sequence[int]] = IDS,
    kinds: Sequence[str] = KINDS,
    periods: Sequence[Sequence[int]] = PERIODS,
    point: Sequence[int] = POINT,
    mirrored: Sequence[Sequence[int]] = MIRRORED,
    *,
    plane: tuple[str, str, Sequence[float], int] | None = None,
    exponents: int | None = K,
    spectra: np.ndarray | None = None,
    leave_out: Sequence[str] = (),
    leave_out_attrs: Sequence[str] = (),
) -> Path:
    """Write a synthetic census file (n = :data:`N`) and return its path.

    ``values``: the swept amplitudes, one per row of ``ids``; None for a census at one point
    (``ids`` then has one row). ``plane``: (first, second, range, points) of a plane census,
    whose starts are then the grid around rest. ``exponents``: k, the exponents per sample
    (:func:`sample_spectra`, or ``spectra`` (P, N, k) when given), with each attractor's mean
    and spread; None for a file written before the census kept them (lambda1 alone).
    ``leave_out``: datasets of /census not to write; ``leave_out_attrs``: its attributes not
    to write.
    """
    path = write_run(path, n=N, strobe=False, events=False, schema_version=2)
    ids = np.asarray(ids, dtype=np.int32)
    points, samples = ids.shape
    a = len(kinds)
    rng = np.random.default_rng(5)
    x0 = np.tile(rng.uniform(-0.3, 0.3, (1, samples, N)), (points, 1, 1))
    v0 = np.tile(rng.uniform(-1.0, 1.0, (1, samples, N)), (points, 1, 1))
    if plane is not None:
        first, second, ranges, m = plane
        x0[:], v0[:] = 0.0, 0.0
        for s in range(samples):
            i, j = s % m, s // m
            for name, k, (lo, hi) in ((first, i, ranges[:2]), (second, j, ranges[2:])):
                target = x0 if name[0] == "x" else v0
                if int(name[1:]) <= N:  # (a bad coordinate is only named in the attribute)
                    target[:, s, int(name[1:]) - 1] = lo + k * (hi - lo) / (m - 1)
    frac = fractions(ids, a)
    with h5py.File(path, "r+") as f:
        del f["final"], f["stats"]
        if values is not None:
            del f["params"].attrs["amplitude"]
        g = f.create_group("census")
        attrs: dict[str, Any] = {
            "samples": np.int32(samples), "seed": np.int32(3), "x_amp": 0.3, "v_amp": 1.0,
            "tolerance": 1e-6, "mirror": "merge",
            "parameter": "amplitude" if values is not None else "",
            "site_distance_limit": 0.2, "chaos_sigmas": 3.0, "rule": "periodic: ...",
        }
        if plane is not None:
            attrs.update(plane=f"{plane[0]} {plane[1]}", plane_range=np.asarray(plane[2]),
                         plane_points=np.int32(plane[3]))
        for name, value in attrs.items():
            if name not in leave_out_attrs:
                g.attrs[name] = value
        if values is not None:
            g["point"] = np.asarray(values, dtype=float)
            g["point"].attrs.update(long_name="amplitude (the swept parameter) at the point",
                                    units="1", model_units="length")
        else:
            g["point"] = np.zeros(1, dtype=np.int32)
            g["point"].attrs.update(long_name="point index", units="1")
        g["point"].make_scale("point")
        axes = [("sample", samples, 1), ("oscillator", N, 1), ("attractor", a, 0),
                ("bond", N + 1, 0)]
        if exponents is not None:
            axes.append(("exponent", exponents, 1))
        for name, count, first_index in axes:
            g[name] = np.arange(first_index, first_index + count, dtype=np.int32)
            g[name].attrs.update(long_name=f"{name} index", units="1")
            g[name].make_scale(name)
        sites = np.zeros((a, N + 1))
        sites[:, 0], sites[:, -1] = 0.5, 0.5
        datasets: dict[str, tuple[Any, str, str]] = {
            "x0": (x0, "point sample oscillator", "length"),
            "v0": (v0, "point sample oscillator", "length/time"),
            "sample_attractor": (ids, "point sample", ""),
            "mirrored": (np.asarray(mirrored, dtype=np.int32), "point sample", ""),
            "lambda1": (np.where(ids == 2, 0.3, -0.05), "point sample", "bit"),
            "attractor_period": (np.asarray(periods, dtype=np.int32).reshape(a, N),
                                 "attractor oscillator", "drive cycles"),
            "attractor_lambda1": (np.linspace(-0.1, 0.3, a), "attractor", "bit"),
            "attractor_lambda1_stderr": (np.full(a, 0.01), "attractor", "bit"),
            "attractor_x": (np.arange(a * N, dtype=float).reshape(a, N) / 100,
                            "attractor oscillator", "length"),
            "attractor_v": (-np.arange(a * N, dtype=float).reshape(a, N) / 100,
                            "attractor oscillator", "length/time"),
            "attractor_point": (np.asarray(point, dtype=np.int32), "attractor", ""),
            "attractor_sample": (np.array([int(np.argmax(ids[min(p, points - 1)] == k)) + 1
                                           for k, p in enumerate(point)], dtype=np.int32),
                                 "attractor", ""),
            "attractor_kind": (np.array(kinds, dtype=h5py.string_dtype()), "attractor", ""),
            "attractor_sites": (sites, "attractor bond", ""),
            "fraction": (frac, "point attractor", ""),
            "fraction_stderr": (np.sqrt(frac * (1 - frac) / samples), "point attractor", ""),
        }
        if exponents is not None:
            if spectra is None:
                spectra = sample_spectra(ids, exponents)
            mean, spread = ensembles(spectra, ids, point, a)
            datasets["lambda1"] = (spectra[:, :, 0], "point sample", "bit")
            datasets.update({
                "sample_exponents": (spectra, "point sample exponent", "bit"),
                "sample_exponents_stderr": (np.full(spectra.shape, 0.02),
                                            "point sample exponent", "bit"),
                "attractor_exponents": (mean, "attractor exponent", "bit"),
                "attractor_exponents_spread": (spread, "attractor exponent", "bit"),
            })
        for name, (data, dims, model_units) in datasets.items():
            if name in leave_out:
                continue
            g[name] = data
            g[name].attrs.update(long_name=name.replace("_", " "), units="1")
            if model_units:
                g[name].attrs["model_units"] = model_units
            for axis, dim in enumerate(dims.split()):
                g[name].dims[axis].attach_scale(g[dim])
    return path


MakeCensus = Callable[..., Path]


@pytest.fixture
def make_census(tmp_path: Path) -> MakeCensus:
    """``make_census(name, **kw)`` writes ``tmp_path/name`` with :func:`write_census`."""

    def make(name: str = "census.h5", **kwargs: Any) -> Path:
        return write_census(tmp_path / name, **kwargs)

    return make


ONE_POINT = {"values": None, "ids": IDS[:1], "kinds": KINDS[:3], "periods": PERIODS[:3],
             "point": POINT[:3], "mirrored": MIRRORED[:1]}
"""The census of point 0 alone, at one parameter point."""

PLANE = {"values": None, "ids": [[0, 0, 1, 0, 1, 1, 2, 1, 1]], "kinds": KINDS[:3],
         "periods": PERIODS[:3], "point": POINT[:3], "mirrored": [[0, 0, 0, 1, 0, 0, 0, 0, 0]],
         "plane": ("x2", "v4", (-0.2, 0.2, -1.0, 1.0), 3)}
"""A 3 x 3 plane of starts (x2, v4) around rest."""


# ---------------------------------------------------------------------------------- reading


def test_reads_every_field(make_census: MakeCensus) -> None:
    path = make_census()
    run = read_run(path)
    census = run.census
    assert isinstance(census, Census) and run.sweep is None and run.continuation is None
    assert (census.parameter, census.samples, census.seed, census.mirror) == \
        ("amplitude", 10, 3, "merge")
    assert (census.x_amp, census.v_amp, census.tolerance) == (0.3, 1.0, 1e-6)
    assert census.swept and census.n_points == 2 and census.n_attractors == 5
    np.testing.assert_array_equal(census.values, VALUES)
    assert census.x0.shape == census.v0.shape == (2, 10, N)
    np.testing.assert_array_equal(census.x0[0], census.x0[1])
    np.testing.assert_array_equal(census.sample_attractor, IDS)
    assert census.mirrored.dtype == bool
    np.testing.assert_array_equal(census.mirrored, np.array(MIRRORED) == 1)
    assert list(census.attractor_kind) == list(KINDS)
    np.testing.assert_array_equal(census.attractor_period, PERIODS)
    np.testing.assert_array_equal(census.attractor_point, POINT)
    np.testing.assert_array_equal(census.attractor_sample, [1, 2, 4, 1, 3])
    assert census.attractor_sites.shape == (5, N + 1)
    assert census.attractor_x.shape == census.attractor_v.shape == (5, N)
    np.testing.assert_array_equal(census.fraction, fractions(IDS, 5))
    np.testing.assert_allclose(census.fraction.sum(axis=1), 1.0, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(census.attractors_at(1), [3, 4])
    assert census.count(0, 0) == 6 and census.count(1, 4) == 2 and census.count(1, 0) == 0
    assert census.plane is None and census.plane_points == 0
    with pytest.raises(ValueError):
        census.fraction[0, 0] = 0.5
    # the swept parameter is not in /params, as in a sweep's file
    assert math.isnan(run.params.amplitude) and run.params.omega == 1.5


def test_labels_and_period_patterns(make_census: MakeCensus) -> None:
    census = read_census(make_census())
    assert [census.label(a) for a in range(5)] == [
        "periodic 1×4", "periodic 2×2 1×2", "chaotic", "periodic 1×4", "aperiodic-nonchaotic"]
    assert census.pattern(2) == "0×4"
    partly = read_census(make_census("partly.h5", periods=PERIODS[:4] + ((8, 0, 0, 0),)))
    assert partly.label(4) == "aperiodic-nonchaotic 8×1 0×3"
    assert period_pattern([8] * 15) == "8×15"
    assert period_pattern([1, 2, 1]) == "1×1 2×1 1×1"
    assert period_pattern([]) == ""


def test_a_census_at_one_point(make_census: MakeCensus) -> None:
    run = read_run(make_census(**ONE_POINT))
    census = run.census
    assert census is not None and not census.swept and census.parameter == ""
    np.testing.assert_array_equal(census.values, [0.0])
    assert run.params.amplitude == 1.7  # the fixture's


def test_xarray_sees_the_dimensions(make_census: MakeCensus) -> None:
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    with xr.open_dataset(make_census(), engine="h5netcdf", group="census") as ds:
        assert ds.x0.dims == ("point", "sample", "oscillator")
        assert ds.fraction.dims == ("point", "attractor")
        assert ds.attractor_sites.dims == ("attractor", "bond")
        np.testing.assert_array_equal(ds.point.values, VALUES)
        np.testing.assert_array_equal(ds.sample.values, np.arange(1, 11))
        shares = ds.fraction.sel(point=2.3).values
        np.testing.assert_array_equal(shares, [0, 0, 0, 0.8, 0.2])
        assert ds.sample_exponents.dims == ("point", "sample", "exponent")
        assert ds.attractor_exponents_spread.dims == ("attractor", "exponent")
        np.testing.assert_array_equal(ds.exponent.values, np.arange(1, K + 1))


def test_a_plane_of_starts(make_census: MakeCensus) -> None:
    census = read_census(make_census(**PLANE))
    assert census.plane == ("x2", "v4") and census.plane_points == 3
    np.testing.assert_array_equal(census.plane_range, [-0.2, 0.2, -1.0, 1.0])
    first, second, ids = census.plane_grid()
    np.testing.assert_allclose(first, [-0.2, 0.0, 0.2], rtol=0, atol=1e-15)
    np.testing.assert_allclose(second, [-1.0, 0.0, 1.0], rtol=0, atol=1e-15)
    np.testing.assert_array_equal(ids, [[0, 0, 1], [0, 1, 1], [2, 1, 1]])
    with pytest.raises(ValueError, match="random starts"):
        read_census(make_census("random.h5", **ONE_POINT)).plane_grid()


@pytest.mark.parametrize("missing", ["fraction", "attractor_kind", "x0", "sample_attractor",
                                     "attractor_period"])
def test_a_missing_dataset_is_named(make_census: MakeCensus, missing: str) -> None:
    with pytest.raises(SchemaError, match=f"no /census/{missing} dataset"):
        read_run(make_census(leave_out=[missing]))


@pytest.mark.parametrize("missing", ["samples", "mirror", "seed"])
def test_a_missing_attribute_is_named(make_census: MakeCensus, missing: str) -> None:
    with pytest.raises(SchemaError, match=f"/census lacks attribute '{missing}'"):
        read_run(make_census(leave_out_attrs=[missing]))


def test_bad_contents_are_refused(make_census: MakeCensus) -> None:
    with pytest.raises(SchemaError, match="sample_attractor holds ids outside 0..4"):
        read_run(make_census("ids.h5", ids=[[0] * 9 + [5], [3] * 10]))
    with pytest.raises(SchemaError, match="attractor_kind holds 'strange'"):
        read_run(make_census("kind.h5", kinds=KINDS[:4] + ("strange",)))
    with pytest.raises(SchemaError, match="attractor_point holds points outside 0..1"):
        read_run(make_census("point.h5", point=(0, 0, 0, 1, 2)))
    with pytest.raises(SchemaError, match="mirrored holds values other than 0 and 1"):
        read_run(make_census("mirror.h5", mirrored=[[2] * 10, [0] * 10]))
    bad_plane = dict(PLANE, plane=("x9", "v4", (-0.2, 0.2, -1.0, 1.0), 3))
    with pytest.raises(SchemaError, match="'x9 v4' is not two coordinates"):
        read_run(make_census("plane.h5", **bad_plane))
    bad_points = dict(PLANE, plane=("x2", "v4", (-0.2, 0.2, -1.0, 1.0), 4))
    with pytest.raises(SchemaError, match="plane_points = 4 does not square to the 9"):
        read_run(make_census("points.h5", **bad_points))


def test_a_file_without_a_census(tmp_path: Path) -> None:
    path = write_run(tmp_path / "run.h5", n=N, schema_version=2)
    assert read_run(path).census is None
    with pytest.raises(SchemaError, match=r"no /census .*not a census file"):
        read_census(path)


def test_census_only_when_asked(make_census: MakeCensus) -> None:
    assert read_run(make_census(), groups=("strobe",)).census is None


def test_reads_the_ensemble_of_spectra(make_census: MakeCensus) -> None:
    census = read_census(make_census())
    ids = np.asarray(IDS)
    spectra = sample_spectra(ids, K)
    assert census.ensemble_stored and census.k == K
    assert census.sample_exponents.shape == census.sample_exponents_stderr.shape == (2, 10, K)
    assert census.attractor_exponents.shape == census.attractor_exponents_spread.shape == \
        (5, K)
    np.testing.assert_array_equal(census.sample_exponents, spectra)
    np.testing.assert_array_equal(census.sample_exponents[..., 0], census.lambda1)
    mean, spread = ensembles(spectra, ids, POINT, 5)
    np.testing.assert_array_equal(census.attractor_exponents, mean)
    np.testing.assert_array_equal(census.attractor_exponents_spread, spread)
    np.testing.assert_array_equal(census.members(1), [1, 5])
    np.testing.assert_array_equal(census.members(3), [0, 1, 3, 4, 5, 6, 8, 9])
    with pytest.raises(ValueError):
        census.sample_exponents[0, 0, 0] = 1.0
    assert read_run(make_census()).unit("census/attractor_exponents") == "bit"


def test_an_older_census_gets_its_ensemble_from_lambda1(make_census: MakeCensus) -> None:
    """A file written before the census kept the samples' exponents: k = 1 from lambda1,
    each attractor's mean and spread those of its samples' lambda1, no standard errors."""
    census = read_census(make_census(exponents=None))
    assert not census.ensemble_stored and census.k == 1
    np.testing.assert_array_equal(census.sample_exponents[..., 0], census.lambda1)
    assert np.isnan(census.sample_exponents_stderr).all()
    ids = np.asarray(IDS)
    for a, p in enumerate(POINT):
        values = census.lambda1[p][ids[p] == a]
        np.testing.assert_allclose(census.attractor_exponents[a], [values.mean()], rtol=1e-15)
        np.testing.assert_allclose(census.attractor_exponents_spread[a],
                                   [values.std(ddof=1)], rtol=1e-15, atol=1e-17)
    # one sample alone: spread 0; -infinity in some members: mean -inf, spread +inf
    alone = read_census(make_census("alone.h5", exponents=None,
                                    ids=[[0, 1, 0, 2, 0, 0, 0, 0, 2, 0], IDS[1]]))
    assert alone.attractor_exponents_spread[1, 0] == 0.0
    assert alone.attractor_exponents[1, 0] == -0.05


def test_a_missing_ensemble_dataset_is_named(make_census: MakeCensus) -> None:
    for missing in ("sample_exponents_stderr", "attractor_exponents",
                    "attractor_exponents_spread"):
        with pytest.raises(SchemaError, match=f"no /census/{missing} dataset"):
            read_run(make_census(f"{missing}.h5", leave_out=[missing]))
    path = make_census("short.h5")
    with h5py.File(path, "r+") as f:
        del f["census/attractor_exponents"]
        f["census/attractor_exponents"] = np.zeros((5, K - 1))
    with pytest.raises(SchemaError, match="attractor_exponents"):
        read_run(path)


# ---------------------------------------------------------------------------------- figures


def bars(ax: Axes) -> list[BarContainer]:
    return [c for c in ax.containers if isinstance(c, BarContainer)]


def test_fractions_at_one_point_are_bars(make_census: MakeCensus) -> None:
    fig = figures.basin_fractions(make_census(**ONE_POINT))
    assert isinstance(fig, Figure)
    ax = fig.axes[0]
    (container,) = bars(ax)
    heights = [patch.get_height() for patch in container.patches]
    np.testing.assert_allclose(heights, fractions(IDS[:1], 3)[0])
    labels = [t.get_text().replace("\n", " ") for t in ax.get_xticklabels()]
    assert labels == ["0: periodic 1×4", "1: periodic 2×2 1×2", "2: chaotic"]
    assert {t.get_text() for t in ax.texts} == {"6/10", "2/10"}
    assert "basin fractions: 10 starts per point; mirror images merged" in ax.get_title()


def test_fractions_along_a_sweep_are_stacked(make_census: MakeCensus) -> None:
    fig = figures.basin_fractions(make_census())
    ax = fig.axes[0]
    segments = bars(ax)
    # one segment per label: 'periodic 1×4' (attractors 0 and 3) is one series
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["periodic 1×4", "periodic 2×2 1×2", "chaotic", "aperiodic-nonchaotic"]
    assert len(segments) == 4
    heights = np.array([[p.get_height() for p in c.patches] for c in segments])
    np.testing.assert_allclose(heights[:, 0], [0.6, 0.2, 0.2, 0.0])
    np.testing.assert_allclose(heights[:, 1], [0.8, 0.0, 0.0, 0.2])
    np.testing.assert_allclose(heights.sum(axis=0), 1.0)
    assert ax.get_xlabel() == "drive amplitude $A$ [length]"
    assert "$A$" not in ax.get_title().split("\n")[0]


def test_the_basin_plane(make_census: MakeCensus) -> None:
    fig = figures.basin_plane(make_census(**PLANE))
    ax = fig.axes[0]
    (image,) = [im for im in ax.get_images() if isinstance(im, AxesImage)]
    index = np.asarray(image.get_array())
    # colour 2k for attractor k, 2k + 1 for its mirror image; rows are v4, columns x2
    np.testing.assert_array_equal(index, [[0, 0, 2], [1, 2, 2], [4, 2, 2]])
    np.testing.assert_allclose(image.get_extent(), [-0.3, 0.3, -1.5, 1.5])
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert labels == ["0: periodic 1×4, 33.3 %", "1: periodic 2×2 1×2, 55.6 %",
                      "2: chaotic, 11.1 %", "lighter: its mirror image"]
    assert ax.get_xlabel() == "initial displacement of oscillator 2 $x_{2}$ [length]"
    assert ax.get_ylabel() == "initial velocity of oscillator 4 $v_{4}$ [length/time]"


def test_the_ensemble_spectra(make_census: MakeCensus) -> None:
    fig = figures.ensemble_spectra(make_census())
    ax = fig.axes[0]
    census = read_census(make_census("again.h5"))
    # each attractor's mean with its spread as error bars, over its samples' spectra
    means = [c for c in ax.containers if isinstance(c, ErrorbarContainer)]
    assert len(means) == 5
    for a, container in enumerate(means):
        line = container.lines[0]
        np.testing.assert_allclose(line.get_ydata(), census.attractor_exponents[a])
        np.testing.assert_allclose(np.diff(line.get_xdata()), 1.0)
        (bars_,) = container.lines[2]
        tops = np.array([segment[1, 1] for segment in bars_.get_segments()])
        np.testing.assert_allclose(tops, census.attractor_exponents[a] +
                                   census.attractor_exponents_spread[a])
    samples = {c.get_gid(): c for c in ax.collections if isinstance(c, LineCollection)
               and str(c.get_gid()).startswith("samples-")}
    assert sorted(samples) == [f"samples-{a}" for a in range(5)]
    assert [len(samples[f"samples-{a}"].get_segments()) for a in range(5)] == [6, 2, 2, 8, 2]
    labels = [t.get_text().replace("\n", " ") for t in ax.get_legend().get_texts()]
    assert labels[0] == "0: periodic 1×4 at $A$ = 2.2, 60 % (6 samples)"
    assert labels[4] == "4: aperiodic-nonchaotic at $A$ = 2.3, 20 % (2 samples)"
    assert [t.get_text() for t in ax.get_xticklabels()] == ["1", "2", "3"]
    assert ax.get_xlabel() == "exponent index $j$ [1]"
    assert ax.get_ylabel() == r"Lyapunov exponent $\lambda_j$ [bit]"  # the file's unit
    assert "the leading 3 exponents of 10 starts per point" in ax.get_title()


def test_the_ensemble_spectra_of_the_largest_exponent(make_census: MakeCensus) -> None:
    """k = 1 (an older file, or exponents = 1): one column, each sample a dot."""
    fig = figures.ensemble_spectra(make_census(**ONE_POINT, exponents=None))
    ax = fig.axes[0]
    dots = [line for line in ax.lines if str(line.get_gid()).startswith("samples-")]
    assert [line.get_xdata().size for line in dots] == [6, 2, 2]
    assert ax.get_xlim() == (0.5, 1.5)
    assert "the largest exponent of 10 starts" in ax.get_title()


def test_the_ensemble_spectra_leave_out_minus_infinity(make_census: MakeCensus) -> None:
    """A direction removed by rests (-infinity) in some samples: drawn without it."""
    spectra = sample_spectra(np.asarray(IDS), K)
    spectra[0, 0, 2] = -np.inf
    with np.errstate(invalid="ignore"):
        path = make_census(spectra=spectra)
    census = read_census(path)
    assert census.attractor_exponents[0, 2] == -np.inf
    fig = figures.ensemble_spectra(path)
    (first,) = [c for c in fig.axes[0].containers if isinstance(c, ErrorbarContainer)][:1]
    assert np.isnan(first.lines[0].get_ydata()[2])


def test_figures_draw_into_given_axes(make_census: MakeCensus) -> None:
    fig = Figure()
    left, middle, right = fig.subplots(1, 3)
    assert figures.basin_fractions(make_census(), ax=left) is fig
    assert figures.basin_plane(make_census("plane.h5", **PLANE), ax=middle) is fig
    assert figures.ensemble_spectra(make_census("spectra.h5"), ax=right) is fig
    assert bars(left) and middle.get_images() and right.containers


def test_figure_errors(make_census: MakeCensus, tmp_path: Path) -> None:
    plain = write_run(tmp_path / "run.h5", n=N, schema_version=2)
    with pytest.raises(SchemaError, match="needed by basin-fractions"):
        figures.basin_fractions(plain)
    with pytest.raises(figures.FigureError, match="needs a plane of starts"):
        figures.basin_plane(make_census())
    with pytest.raises(figures.FigureError, match="point 1 is outside 0..0"):
        figures.basin_plane(make_census("plane.h5", **PLANE), point=1)


def test_cli_commands(make_census: MakeCensus, tmp_path: Path,
                      capsys: pytest.CaptureFixture[str]) -> None:
    sweep, plane = make_census(), make_census("plane.h5", **PLANE)
    assert main(["basin-fractions", str(sweep), "-o", str(tmp_path / "f.png")]) == 0
    assert main(["basin-plane", str(plane), "-o", str(tmp_path / "p.png")]) == 0
    assert (tmp_path / "f.png").stat().st_size > 0 and (tmp_path / "p.png").stat().st_size > 0
    assert main(["basin-plane", str(sweep), "-o", str(tmp_path / "bad.png")]) == 2
    assert "needs a plane of starts" in capsys.readouterr().err
    assert not (tmp_path / "bad.png").exists()
    assert main(["all", str(plane), "-o", str(tmp_path / "all")]) == 0
    made = capsys.readouterr().out.split()
    assert made == [str(tmp_path / "all_basin_fractions.png"),
                    str(tmp_path / "all_basin_plane.png"),
                    str(tmp_path / "all_ensemble_spectra.png")]
    # the largest exponent alone (k = 1): no ensemble of spectra among 'all'
    older = make_census("older.h5", **PLANE, exponents=None)
    assert main(["all", str(older), "-o", str(tmp_path / "older")]) == 0
    assert capsys.readouterr().out.split() == [str(tmp_path / "older_basin_fractions.png"),
                                               str(tmp_path / "older_basin_plane.png")]
    assert main(["ensemble-spectra", str(sweep), "-o", str(tmp_path / "e.png")]) == 0
    assert (tmp_path / "e.png").stat().st_size > 0
    plain = write_run(tmp_path / "run.h5", n=N, schema_version=2)
    assert main(["ensemble-spectra", str(plain), "-o", str(tmp_path / "bad.png")]) == 2
    assert "no /census" in capsys.readouterr().err
    assert not (tmp_path / "bad.png").exists()


# ---------------------------------------------------------------- censuses by the simulator


CHAIN = ("&chain n = 15, amplitude = 2.2, omega = 1.5, damping = 0.05, restitution = 0.7 /\n"
         "&run transient = 300, cycles = 32, max_period = 8 /\n")


def run_simulator(exe: Path, tmp_path: Path, text: str, name: str) -> Path:
    (tmp_path / f"{name}.nml").write_text(text + f"&output file = '{name}.h5' /\n")
    result = subprocess.run([str(exe), "--quiet", f"{name}.nml"], cwd=tmp_path,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    return tmp_path / f"{name}.h5"


def test_a_census_run_along_a_sweep(simulator: Path, tmp_path: Path) -> None:
    path = run_simulator(simulator, tmp_path, CHAIN + (
        "&census samples = 6, seed = 4, x_amp = 0.3, v_amp = 1.0 /\n"
        "&sweep parameter = 'amplitude', start = 2.2, stop = 2.3, step = 0.1 /\n"), "sweep")
    run = read_run(path)
    census = run.census
    assert census is not None and census.parameter == "amplitude"
    assert math.isnan(run.params.amplitude)
    with h5py.File(path) as f:
        g = f["census"]
        np.testing.assert_array_equal(census.values, g["point"][()])
        np.testing.assert_array_equal(census.sample_attractor, g["sample_attractor"][()])
        np.testing.assert_array_equal(census.fraction, g["fraction"][()])
        np.testing.assert_array_equal(census.attractor_x, g["attractor_x"][()])
    assert set(census.attractor_kind) <= set(ATTRACTOR_KINDS)
    np.testing.assert_allclose(census.fraction.sum(axis=1), 1.0, rtol=0, atol=1e-12)
    for p in range(2):
        for a in census.attractors_at(p):
            assert census.fraction[p, a] == census.count(p, int(a)) / 6
    assert run.unit("census/x0") == "length"
    assert run.unit("census/lambda1") == "bits per drive cycle"
    xr = pytest.importorskip("xarray")
    pytest.importorskip("h5netcdf")
    with xr.open_dataset(path, engine="h5netcdf", group="census") as ds:
        np.testing.assert_array_equal(ds.fraction.values, census.fraction)
        assert ds.point.attrs["model_units"] == "length"
    fig = figures.basin_fractions(run)
    assert len(bars(fig.axes[0])) == len({census.label(a) for a in range(census.n_attractors)})


def test_a_plane_census_run(simulator: Path, tmp_path: Path) -> None:
    path = run_simulator(simulator, tmp_path, CHAIN + (
        "&initial kind = 'explicit', x0 = 15*0.01, v0 = 15*-0.02 /\n"
        "&census plane = 'x8', 'v8', plane_range = -0.3, 0.3, -1, 1, plane_points = 4 /\n"),
        "plane")
    census = read_census(path)
    assert census.plane == ("x8", "v8") and census.plane_points == 4 and census.samples == 16
    first, second, ids = census.plane_grid()
    # from the index: lo + k ((hi - lo) / (m - 1)), and hi itself at the end
    np.testing.assert_array_equal(first, [-0.3 + k * (0.6 / 3) for k in range(3)] + [0.3])
    np.testing.assert_array_equal(second, [-1 + k * (2 / 3) for k in range(3)] + [1])
    others = np.delete(census.x0[0], 7, axis=1)
    assert (others == 0.01).all() and (np.delete(census.v0[0], 7, axis=1) == -0.02).all()
    np.testing.assert_array_equal(ids.ravel(), census.sample_attractor[0])
    fig = figures.basin_plane(path)
    assert fig.axes[0].get_images()


def test_an_ensemble_census_run(simulator: Path, tmp_path: Path) -> None:
    """Full spectra (exponents = 2n = 8) of a chain of four at two amplitudes: the reader
    gives the file's arrays, each attractor's mean and spread are its samples' (numpy, n - 1),
    the first exponent is lambda1, and the figure draws every sample."""
    path = run_simulator(simulator, tmp_path, (
        "&chain n = 4, amplitude = 1.0, omega = 0.9, damping = 0.05, restitution = 0.7 /\n"
        "&run transient = 300, cycles = 200, max_period = 8 /\n"
        "&census samples = 12, seed = 3, x_amp = 0.3, v_amp = 1.0, exponents = 8 /\n"
        "&sweep parameter = 'amplitude', start = 1.0, stop = 1.1, step = 0.1 /\n"), "ensemble")
    census = read_census(path)
    assert census.ensemble_stored and census.k == 8
    with h5py.File(path) as f:
        g = f["census"]
        for name in ("sample_exponents", "sample_exponents_stderr", "attractor_exponents",
                     "attractor_exponents_spread"):
            np.testing.assert_array_equal(getattr(census, name), g[name][()], err_msg=name)
    np.testing.assert_array_equal(census.sample_exponents[..., 0], census.lambda1)
    assert (np.diff(census.sample_exponents, axis=2) <= 0).all()
    assert (census.sample_exponents_stderr >= 0).all()
    for a in range(census.n_attractors):
        values = census.sample_exponents[census.attractor_point[a]][census.members(a)]
        np.testing.assert_allclose(census.attractor_exponents[a], values.mean(axis=0),
                                   rtol=1e-13, atol=1e-14)
        spread = values.std(axis=0, ddof=1) if values.shape[0] > 1 else np.zeros(8)
        np.testing.assert_allclose(census.attractor_exponents_spread[a], spread, rtol=1e-12,
                                   atol=1e-14)
    fig = figures.ensemble_spectra(path)
    drawn = {c.get_gid(): len(c.get_segments()) for c in fig.axes[0].collections
             if str(c.get_gid()).startswith("samples-")}
    assert drawn == {f"samples-{a}": census.members(a).size
                     for a in range(census.n_attractors)}
    assert sum(drawn.values()) == 24
