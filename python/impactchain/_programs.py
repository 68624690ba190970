"""The command-line programs installed with the package, as console scripts on the
environment's PATH: ``impactchain`` (the simulator) and ``impactchain-mpi`` (the MPI driver
of sweeps and censuses, built when the machine had MPI for Fortran). meson.build compiles
them into ``impactchain/bin/``; each entry point here replaces the Python process with the
program (``os.execv``), so its signals, standard streams and exit status are the program's
own."""

from __future__ import annotations

import os
import sys
from pathlib import Path

BIN = Path(__file__).resolve().parent / "bin"


def _run(name: str, missing: str) -> None:
    program = BIN / name
    if not program.is_file():
        print(f"{name}: error: not installed with this package ({missing})", file=sys.stderr)
        raise SystemExit(2)
    os.execv(program, [str(program), *sys.argv[1:]])


def simulator() -> None:
    """``impactchain [options] input.nml``: the simulator (``impactchain --help``)."""
    _run("impactchain", "the package was built without its programs")


def mpi_driver() -> None:
    """``mpirun -np N impactchain-mpi [options] input.nml``: sweeps and censuses over MPI."""
    _run("impactchain-mpi", "MPI for Fortran was not found when the package was built: "
         "install it (Debian: libopenmpi-dev) and reinstall the package")
