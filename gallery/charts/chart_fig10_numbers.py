"""The numbers docs/gallery.md quotes for figure 10's chain in (A, w), read from the runs of
`make figures/chart_fig10.png` (figures/runs/chart_fig10_*.h5):

    .venv/bin/python gallery/charts/chart_fig10_numbers.py
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from impactchain.figures import chain_period, map_grid
from impactchain.io import read_run

RUNS = "figures/runs/chart_fig10_"
DAMPING, SPACING = 0.05, 1.0


def grazing(w: np.ndarray | float, damping: float = DAMPING) -> np.ndarray | float:
    """The forced response's grazing amplitude, a sqrt((1 - w^2)^2 + (2 b w)^2)."""
    return SPACING * np.hypot(1 - np.square(w), 2 * damping * np.asarray(w))


def main() -> None:
    curves = {name: read_run(f"{RUNS}{name}.h5").curve
              for name in ("grazing_down", "grazing_up", "fold_down", "fold_up")}
    for name, c in curves.items():
        if c.follow == "grazing":
            check = f"|A - closed form| <= {np.abs(c.values - grazing(c.values2)).max():.1e}"
        else:
            check = f"|multiplier - 1| <= {np.abs(c.multipliers - 1).min(axis=1).max():.1e}"
        codim2 = [(str(k), round(float(c.values[i]), 4), round(float(c.values2[i]), 4))
                  for i, k in zip(c.codim2_index, c.codim2_kind)]
        print(f"{name}: {c.values.size} points, (A, w) from ({c.values[0]:.10f}, "
              f"{c.values2[0]:.4f}) to ({c.values[-1]:.4f}, {c.values2[-1]:.4f}), "
              f"{check}, ends: {c.end_reason}; codim-2 points {codim2}")
    down, up = curves["fold_down"], curves["fold_up"]
    fold = CubicSpline(np.r_[down.values2[::-1], up.values2[1:]],
                       np.r_[down.values[::-1], up.values[1:]])
    w = brentq(lambda x: fold(x) - grazing(x), 1.6, 1.85)
    print(f"fold and grazing curves cross at w = {w:.4f}, A = {float(grazing(w)):.4f}")
    for x in (1.6, 1.7, 1.8, 1.9, 2.0):
        print(f"  w = {x}: fold at A = {float(fold(x)):.4f}, grazing at {grazing(x):.4f}")
    for b in (0.05, 0.10, 0.15):
        print(f"A = 2, b = {b}: grazing at w = "
              f"{brentq(lambda x: grazing(x, b) - 2, 1.0, 3.0):.5f}")
    sweep = read_run(f"{RUNS}map.h5").sweep
    a, ws, impacts = map_grid(sweep, "amplitude", "omega", sweep.collisions_per_cycle)
    period = map_grid(sweep, "amplitude", "omega", chain_period(sweep.period))[2]
    row = int(np.argmin(abs(ws - 1.9)))
    print(f"map {a.size} x {ws.size}; the row w = 1.9 going down in A, where it changes:")
    last = None
    for i in range(a.size - 1, -1, -1):
        now = (round(float(impacts[row, i]), 1), int(period[row, i]))
        if now != last:
            print(f"  A = {a[i]:.2f}: {impacts[row, i]:.2f} impacts per cycle, period {now[1]}")
            last = now
    above, bracketed = [], 0
    for j, x in enumerate(ws):
        eight = np.isclose(impacts[j], 8) & (period[j] == 1)
        if not (down.values2[-1] <= x <= up.values2[-1] and eight.any()):
            continue
        i = int(np.nonzero(eight)[0].min())
        above.append(a[i] - float(fold(x)))
        bracketed += bool(i > 0 and a[i - 1] <= fold(x) <= a[i])
    print(f"rows with eight impacts of period 1: {len(above)}; their smallest A lies "
          f"{min(above):.4f} to {max(above):.4f} above the fold curve, within one step "
          f"in {bracketed} rows")
    free = [a[np.isclose(impacts[j], 0)].max() - grazing(x) for j, x in enumerate(ws)
            if np.isclose(impacts[j], 0).any()]
    print(f"rows with a non-impacting point: {len(free)}; its largest A lies at least "
          f"{-max(free):.3f} below the grazing curve")


if __name__ == "__main__":
    main()
