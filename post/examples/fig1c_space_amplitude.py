"""Figure 1c of the paper through the Python API alone: no namelist, no HDF5 file.

The space-amplitude plot of 16 oscillators (A = 1.7, w = 1.5, b = 0.05, K = 0.7, fixed
walls): the displacement of every oscillator at the Poincare section, one line per drive
cycle, for 200 cycles after a transient, from the seeded random start of
``namelists/fig1c.nml``. The numbers are bit-identical to ``fpm run --profile release --
namelists/fig1c.nml`` (post/tests/test_api.py checks it).

Usage::

    .venv/bin/python post/examples/fig1c_space_amplitude.py fig1c.png
    .venv/bin/python post/examples/fig1c_space_amplitude.py fig1c.png --amplitude 1.8
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # run from anywhere

from post import api  # noqa: E402

N = 16


def compute(amplitude: float = 1.7, omega: float = 1.5, transient: int = 2000,
            cycles: int = 200, seed: int = 1) -> api.Simulation:
    """The run of namelists/fig1c.nml: &initial kind='random', x_amp=0.3, v_amp=1.0."""
    x0, v0 = api.random_start(N, seed=seed, x_amp=0.3, v_amp=1.0)
    return api.simulate(N, amplitude, omega, damping=0.05, restitution=0.7, spacing=1.0,
                        boundary="fixed", x0=x0, v0=v0, transient=transient, cycles=cycles,
                        events=False)


def draw(sim: api.Simulation, title: str) -> Figure:
    """Strobe displacement against equilibrium position, walls as thick lines."""
    n = sim.x.shape[1]
    position = np.arange(1, n + 1, dtype=float)  # equilibrium of oscillator i: i a, a = 1
    fig = Figure(figsize=(8.0, 5.0), layout="constrained")
    ax = fig.add_subplot()
    ax.plot(position, sim.x.T, color="tab:blue", linewidth=0.5, marker="o", markersize=1.8)
    for wall in (0.0, n + 1.0):
        ax.axvline(wall, color="black", linewidth=3)
    for i, p in enumerate(sim.periods):
        ax.text(position[i], 1.01, "c" if p == 0 else str(p), ha="center", va="bottom",
                fontsize=7, transform=ax.get_xaxis_transform())
    ax.set_xlim(-0.5, n + 1.5)
    ax.set_xlabel("equilibrium position [length]")
    ax.set_ylabel("displacement $x_i$ at the section [length]")
    ax.set_title(f"{title}\nlast {sim.x.shape[0]} cycles (labels: period, c = none found)",
                 fontsize="medium", pad=14)
    return fig


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", type=Path, help="PNG file to write")
    parser.add_argument("--amplitude", type=float, default=1.7)
    parser.add_argument("--omega", type=float, default=1.5)
    parser.add_argument("--transient", type=int, default=2000)
    parser.add_argument("--cycles", type=int, default=200)
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    try:
        sim = compute(args.amplitude, args.omega, args.transient, args.cycles, args.seed)
    except (ValueError, ImportError) as exc:
        parser.error(str(exc))
    title = (f"n = {N}, A = {args.amplitude:g}, w = {args.omega:g}, b = 0.05, K = 0.7, "
             f"fixed walls")
    draw(sim, title).savefig(args.output, dpi=150)
    print(f"wrote {args.output} ({sim.collisions_per_cycle:.2f} collisions per cycle)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
