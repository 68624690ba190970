"""The numbers docs/gallery.md quotes for the paper's default chain in (A, w), read from the
runs of `make figures/chart_default.png` (figures/runs/chart_default_*.h5):

    .venv/bin/python gallery/charts/chart_default_numbers.py
"""

from __future__ import annotations

import numpy as np

from impactchain import api
from impactchain.figures import map_grid
from impactchain.io import read_run

RUNS = "figures/runs/chart_default_"
DAMPING, SPACING = 0.05, 1.0
CHAIN = dict(n=16, damping=DAMPING, restitution=0.7, spacing=SPACING, boundary="fixed")


def grazing(w: np.ndarray | float) -> np.ndarray | float:
    """The forced response's grazing amplitude, a sqrt((1 - w^2)^2 + (2 b w)^2)."""
    return SPACING * np.hypot(1 - np.square(w), 2 * DAMPING * np.asarray(w))


def free_exponent(w: np.ndarray | float) -> np.ndarray | float:
    """Every exponent of the chain without impacts: -b T in bits per drive cycle."""
    return -DAMPING * 2 * np.pi / np.asarray(w) / np.log(2)


def main() -> None:
    for name in ("grazing_down", "grazing_up", "fold_down", "fold_up"):
        c = read_run(f"{RUNS}{name}.h5").curve
        if c.follow == "grazing":
            check = f"|A - closed form| <= {np.abs(c.values - grazing(c.values2)).max():.1e}"
        else:
            check = f"|multiplier - 1| <= {np.abs(c.multipliers - 1).min(axis=1).max():.1e}"
        print(f"{name}: {c.values.size} points, (A, w) from ({c.values[0]:.7f}, "
              f"{c.values2[0]:.4f}) to ({c.values[-1]:.4f}, {c.values2[-1]:.4f}), {check}, "
              f"ends: {c.end_reason}")
    sweep = read_run(f"{RUNS}map.h5").sweep
    a, ws, largest = map_grid(sweep, "amplitude", "omega", sweep.exponents[:, 0])
    impacts = map_grid(sweep, "amplitude", "omega", sweep.collisions_per_cycle)[2]
    left = a[None, :] < grazing(ws)[:, None]
    print(f"map {a.size} x {ws.size} = {a.size * ws.size} points, A {a[0]:.1f}..{a[-1]:.1f}, "
          f"w {ws[0]:.2f}..{ws[-1]:.2f}")
    free = np.isclose(impacts, 0)
    print(f"left of the grazing curve: {left.sum()} points, {(left & free).sum()} without "
          f"impacts, their largest exponent within "
          f"{np.abs(largest - free_exponent(ws)[:, None])[free].max():.1e} of -bT; "
          f"{(left & ~free).sum()} impacting (hysteresis: the sweep comes down from A = 6)")
    chaotic = largest > 0.01
    print(f"right of it: {(~left).sum()} points, {(chaotic & ~left).sum()} with a largest "
          f"exponent above 0.01 bits/cycle ({(chaotic & left).sum()} left of it)")
    for w in (1.5, 1.9):
        j = int(np.argmin(abs(ws - w)))
        row = chaotic[j]
        spans = np.flatnonzero(np.diff(np.r_[0, row.astype(int), 0]))
        runs_ = [(round(float(a[s]), 1), round(float(a[e - 1]), 1))
                 for s, e in zip(spans[::2], spans[1::2])]
        print(f"row w = {ws[j]:.2f}: grazing at A = {float(grazing(ws[j])):.4f}; chaotic "
              f"(largest exponent > 0.01) over A in {runs_}")
    high = ws >= 2.3 - 1e-9
    distance = a[None, :] - grazing(ws)[:, None]
    rim = high[:, None] & (distance >= 0) & (distance < 0.4)
    beyond = high[:, None] & (distance >= 0.4)
    print(f"w >= 2.3, right of the curve: chaotic at {(chaotic & rim).sum()} of {rim.sum()} "
          f"points within 0.4 of it, at {(chaotic & beyond).sum()} of {beyond.sum()} beyond")
    born_at_grazing()
    j, i = int(np.argmin(abs(ws - 1.5))), int(np.argmin(abs(a - 1.7)))
    print(f"the default point (A, w) = ({a[i]:.2f}, {ws[j]:.2f}): largest exponent "
          f"{largest[j, i]:.3f} bits/cycle, {impacts[j, i]:.2f} impacts per cycle")


def born_at_grazing() -> None:
    """The default chain at w = 1.5 from rest, A from 1 up through its grazing: where the
    period-1 orbit with the new wall impacts goes."""
    run = api.continuation(amplitude=1.0, omega=1.5, parameter="amplitude", stop=2.2,
                           step=0.02, max_points=400, transient=300, kind="rest", **CHAIN)
    values, impacts = run["values"].values, run["impacts_per_period"].values
    kinds = [str(k) for k in run["special_kind"].values]
    g = int(run["special_index"].values[kinds.index("grazing")])
    past = slice(g + 1, None)
    largest = np.abs(run["multipliers_re"].values + 1j * run["multipliers_im"].values).max(1)
    print(f"w = 1.5 from rest: grazing at A = {float(run['special_value'][0]):.10f}; past it "
          f"the orbit with {int(impacts[g + 1])} impacts per cycle runs from A = "
          f"{values[g + 1]:.5f} down to {values[-1]:.4f}, unstable at every point (largest "
          f"|multiplier| {largest[past].min():.2f} to {largest[past].max():.3g}); ends: "
          f"{run.attrs['end_reason']}")


if __name__ == "__main__":
    main()
