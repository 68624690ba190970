"""figures.chart: the lines drawn are the curves' points, the map is the sweep's grid (its
extent, its cells in place whatever the sweep's order and direction), on a tiny grid of
figure 10's chain."""
from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from impactchain import api, figures
from test_api import FIG10

pytest.importorskip("xarray")

# figure 10's fold (A = 2.885 at w = 1.9) and its forced response's grazing (A = 2.617)
FOLD = dict(amplitude=3.0, parameter="amplitude", stop=2.0, step=-0.05, max_points=8,
            follow="fold", parameter2="omega", stop2=1.95, step2=0.01)
GRAZING = dict(amplitude=1.0, parameter="amplitude", stop=3.0, step=0.1, max_points=10,
               follow="grazing", parameter2="omega", stop2=1.7, step2=-0.05)
# A down from 3 (as figure 10 sweeps it), 3 x 3 points, a few cycles each, with the
# largest exponent
MAP = dict(amplitude=3.0, omega=1.88, transient=5, cycles=6, parameter="amplitude",
           start=3.0, stop=2.6, step=-0.2, parameter2="omega", start2=1.88, stop2=1.92,
           step2=0.02, lyapunov=True, vectors=2)
SWAPPED = dict(MAP, parameter="omega", start=1.88, stop=1.92, step=0.02,
               parameter2="amplitude", start2=3.0, stop2=2.6, step2=-0.2)


@pytest.fixture(scope="module")
def curves() -> list[Any]:
    return [api.curve(**FIG10, **FOLD), api.curve(**FIG10, **GRAZING)]


@pytest.fixture(scope="module")
def sweep() -> Any:
    return api.sweep(**{**FIG10, **MAP})


def _map(ax: Any) -> Any:
    (image,) = [i for i in ax.images if i.get_gid() == "map"]
    return image


def test_lines_are_the_curves_points(curves: list[Any], sweep: Any) -> None:
    ax = figures.chart(curves, over=sweep).axes[0]
    for tree in curves:
        curve = tree["curve"]
        (line,) = [line for line in ax.lines
                   if line.get_gid() == f"curve-{curve.attrs['follow']}"]
        assert curve.sizes["curve_point"] > 1
        assert np.array_equal(line.get_xdata(), curve["values"].values)
        assert np.array_equal(line.get_ydata(), curve["values2"].values)
    assert "amplitude" in ax.get_xlabel() and "frequency" in ax.get_ylabel()


def _value(point: Any, quantity: str) -> int:
    """What the map shows at one point of the sweep."""
    if quantity == "period":
        return int(figures.chain_period(point["period"].values[None, :])[0])
    return int(min(np.rint(point["collisions_per_cycle"].values), figures.IMPACTS_CAP + 1))


def test_exponent_map_is_the_largest_exponent(curves: list[Any], sweep: Any) -> None:
    """Each cell the largest exponent of its point, on a scale centred at zero that reaches
    the grid's EXPONENT_SCALE percentile of |exponent|."""
    ax = figures.chart(curves, over=sweep, quantity="exponent").axes[0]
    image = _map(ax)
    assert image.get_extent() == pytest.approx((2.5, 3.1, 1.87, 1.93), abs=1e-12)
    values = np.array([[float(sweep.sel(point=a, point2=w, method="nearest")["exponents"][0])
                        for a in (2.6, 2.8, 3.0)] for w in (1.88, 1.90, 1.92)])
    assert np.array_equal(np.asarray(image.get_array()), values)  # rows: w up
    norm = image.norm
    reach = np.percentile(np.abs(values), figures.EXPONENT_SCALE)
    assert norm.vcenter == 0 and norm.vmin == -norm.vmax == -reach


def test_exponent_map_needs_exponents(curves: list[Any]) -> None:
    plain = api.sweep(**{**FIG10, **MAP, "lyapunov": False})
    with pytest.raises(figures.FigureError, match="lyapunov"):
        figures.chart(curves, over=plain, quantity="exponent")


@pytest.mark.parametrize("quantity", ("period", "impacts"))
def test_map_extent_is_the_grid(curves: list[Any], sweep: Any, quantity: str) -> None:
    """Cells centred on the grid's points (A 2.6, 2.8, 3.0; w 1.88, 1.90, 1.92), the axes'
    limits theirs, each cell the value of its point (the sweep ran A down)."""
    ax = figures.chart(curves, over=sweep, quantity=quantity).axes[0]
    image = _map(ax)
    expected = (2.5, 3.1, 1.87, 1.93)
    assert image.get_extent() == pytest.approx(expected, abs=1e-12)
    assert (*ax.get_xlim(), *ax.get_ylim()) == pytest.approx(expected, abs=1e-12)
    points = [[sweep.sel(point=a, point2=w, method="nearest") for a in (2.6, 2.8, 3.0)]
              for w in (1.88, 1.90, 1.92)]
    values = np.array([[_value(p, quantity) for p in row] for row in points])
    assert len(np.unique(values[0])) > 1 or quantity == "period"  # (the order is seen)
    present = np.unique(values)
    assert np.array_equal(present[np.asarray(image.get_array())], values)  # rows: w up


def test_either_order_of_the_sweep_draws_the_same_map(curves: list[Any], sweep: Any) -> None:
    swapped = api.sweep(**{**FIG10, **SWAPPED})
    # (the exponents over six cycles differ with the path each point was reached by)
    for quantity in ("period", "impacts"):
        one = _map(figures.chart(curves, over=sweep, quantity=quantity).axes[0])
        two = _map(figures.chart(curves, over=swapped, quantity=quantity).axes[0])
        assert one.get_extent() == pytest.approx(two.get_extent(), abs=1e-12)
        assert np.array_equal(one.get_array(), two.get_array())


def test_wrong_map_or_quantity_is_refused(curves: list[Any], sweep: Any) -> None:
    with pytest.raises(figures.FigureError, match="quantity"):
        figures.chart(curves, over=sweep, quantity="largest")
    other = api.sweep(**{**FIG10, **MAP, "parameter2": "damping", "start2": 0.05,
                         "stop2": 0.06, "step2": 0.01})
    with pytest.raises(figures.FigureError, match="damping"):
        figures.chart(curves, over=other)


def test_without_a_map_the_limits_hold_every_point(curves: list[Any]) -> None:
    ax = figures.chart(curves).axes[0]
    assert not ax.images
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    for tree in curves:
        curve = tree["curve"]
        assert x0 < curve["values"].min() and curve["values"].max() < x1
        assert y0 < curve["values2"].min() and curve["values2"].max() < y1
