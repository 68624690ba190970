"""The attractor census: :func:`census` (public through :mod:`impactchain.api`).

The extension has no census: a census's file (samples, attractors, their spectra, mirror
images, planes of starts) is the product the command line already writes, so :func:`census`
runs the installed program on a temporary input and returns its file as xarray reads it.
Every key goes as the program's own ``--set group.key=value``: the numbers, checks and
messages are the command line's by construction.
"""

from __future__ import annotations

import os
import subprocess
import tempfile
from pathlib import Path
from typing import Any

from impactchain._calls import _float, _int64, _keys, _n, _namelist_value
from impactchain._programs import BIN
from impactchain.schema import SCHEMA_DEFAULT, with_schema_defaults

_STOPPED = 3  # the program's exit status when stopped (Ctrl-C) before the census ended


@with_schema_defaults
def census(
    n: int,
    amplitude: float,
    omega: float,
    *,
    samples: int,
    cycles: int = SCHEMA_DEFAULT,
    threads: int = 0,
    **keys: Any,
) -> Any:
    """An attractor census (docs/model.md section 13): ``samples`` random starts (``&census
    seed``, ``x_amp``, ``v_amp``; or a plane of starts, ``plane``, ``plane_range``,
    ``plane_points``), each run through ``transient`` and ``cycles`` drive cycles and
    classified; the CLI's ``&census``. ``**keys``: any other key of the input table, as
    :func:`simulate`'s (seed, x_amp, v_amp name the &census keys here). Starts run on
    ``threads`` OpenMP threads (0: ``OMP_NUM_THREADS``, else every core); the numbers do not
    depend on the count.

    Returns:
        An :class:`xarray.DataTree`, the CLI's census file (``xarray.open_datatree(path)``):
        ``/params``, ``/census`` (every sample's attractor, the attractors, their fractions
        and exponents) with the file's names, dimensions and units, loaded into memory.

    Raises:
        ImportError: xarray is missing, or the package was built without its programs.
        ValueError: a bad argument, with the CLI's message. RuntimeError: the run failed.
        KeyboardInterrupt: Ctrl-C.
    """
    try:
        import xarray as xr
    except ImportError:
        raise ImportError("api.census returns an xarray.DataTree: pip install xarray") from None
    program = BIN / "impactchain"
    if not program.is_file():
        raise ImportError(f"api.census runs the program {program}, which this package was "
                          "built without")
    given = {("census", "samples"): _int64(samples, "&census: samples", ">= 1"),
             ("run", "cycles"): _int64(cycles, "&run: cycles", "[1, 1e12]"),
             **_keys(keys, ("census",))}
    settings = [word for (group, key), value in given.items()
                for word in ("--set", f"{group}.{key}={_namelist_value(value)}")]
    environment = dict(os.environ)
    if threads:
        environment["OMP_NUM_THREADS"] = str(_int64(threads, "threads", ">= 0"))
    with tempfile.TemporaryDirectory(prefix="impactchain-census-") as folder:
        source = Path(folder) / "census.nml"
        source.write_text(f"&chain n = {_n(n)}, amplitude = {_float(amplitude, 'amplitude')!r}, "
                          f"omega = {_float(omega, 'omega')!r} /\n")
        command = [str(program), "--quiet", *settings, "-o", str(Path(folder) / "census.h5")]
        check = subprocess.run([*command, "--check", str(source)], capture_output=True,
                               text=True, env=environment)
        if check.returncode != 0:
            raise ValueError(_message(check.stderr))
        result = subprocess.run([*command, str(source)], capture_output=True, text=True,
                                env=environment)
        if result.returncode == _STOPPED:
            raise KeyboardInterrupt(_message(result.stderr))
        if result.returncode != 0:
            raise RuntimeError(_message(result.stderr))
        tree = xr.open_datatree(Path(folder) / "census.h5", engine="h5netcdf")
        tree.load()
        tree.close()
    return tree


def _message(stderr: str) -> str:
    """The program's message without its ``impactchain: error:`` prefix."""
    return stderr.strip().removeprefix("impactchain: error: ")
