"""Figure 1c of the paper through the Python API alone: no namelist, no HDF5 file.

The space-amplitude plot of 16 oscillators (A = 1.7, w = 1.5, b = 0.05, K = 0.7, fixed
walls): the displacement of every oscillator at the Poincare section, one line per drive
cycle, for 200 cycles after a transient, from the seeded random start of
``namelists/fig1c.nml``. The numbers are bit-identical to ``fpm run --profile release --
namelists/fig1c.nml`` (test/python/package/test_api.py checks it). The figure is the gallery's own,
``impactchain.figures.space_amplitude``, which takes the in-memory result as it takes a file;
the PNG's metadata hold the equivalent input namelist.

Usage, with the package installed (``pip install .`` or ``make``), from any directory::

    .venv/bin/python examples/python/fig1c_space_amplitude.py fig1c.png
    .venv/bin/python examples/python/fig1c_space_amplitude.py fig1c.png --amplitude 1.8
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from matplotlib.figure import Figure

from impactchain import api, figures

N = 16


def compute(amplitude: float = 1.7, omega: float = 1.5, transient: int = 2000,
            cycles: int = 200, seed: int = 1) -> api.Simulation:
    """The run of namelists/fig1c.nml: &initial kind='random', x_amp=0.3, v_amp=1.0."""
    x0, v0 = api.random_start(N, seed=seed, x_amp=0.3, v_amp=1.0)
    return api.simulate(N, amplitude, omega, damping=0.05, restitution=0.7, spacing=1.0,
                        boundary="fixed", x0=x0, v0=v0, transient=transient, cycles=cycles,
                        events=False)


def draw(sim: api.Simulation, seed: int) -> Figure:
    """The gallery's space-amplitude figure of the in-memory result (impactchain.figures)."""
    return figures.space_amplitude(sim, labels=[f"random start, seed {seed}"])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("output", type=Path, help="PNG (or .pdf, .svg) file to write")
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
    figures.save(draw(sim, args.seed), args.output, dpi=150)
    print(f"wrote {args.output} ({sim.collisions_per_cycle:.2f} collisions per cycle)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
