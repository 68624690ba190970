"""Provenance (issue #29, item 5; src/base/chain_provenance.f90): `impactchain --version`, the MPI
driver's `--version`, the root attributes of every kind of output file (run, sweep,
continuation, census) and `impactchain.api.provenance()` name the code version, the compiler
and its flags, the BLAS with its version and the kernels it selected on this CPU, and the CPU
model, and agree."""
from __future__ import annotations

import os
import subprocess

import h5py
import pytest

from simulator import impactchain_exe, mpi_exe, run_namelist  # noqa: F401 (fixtures)

KEYS = ("code_version", "compiler", "compiler_options", "blas", "blas_kernel", "cpu_model")
#: what every build shares on one machine (compiler_options name each build's directories)
SHARED = ("code_version", "compiler", "blas", "blas_kernel", "cpu_model")

RUN = """
&chain n = 4, amplitude = 1.7, omega = 1.5 /
&initial kind = 'random', seed = 3, x_amp = 0.3, v_amp = 0.3 /
&run transient = 5, cycles = 10 /
&lyapunov enabled = .true. /
&output file = 'run.h5' /
"""
SWEEP = RUN + """
&sweep parameter = 'amplitude', start = 1.5, stop = 1.7, step = 0.1, mode = 'independent' /
"""
CONTINUATION = """
&chain n = 4, amplitude = 2.6, omega = 1.9, damping = 0.05, restitution = 0.5 /
&initial kind = 'rest' /
&run transient = 200 /
&continuation parameter = 'amplitude', stop = 2.5, step = -0.02, max_points = 10 /
&output file = 'run.h5' /
"""

CENSUS = """
&chain n = 4, amplitude = 1.7, omega = 1.5 /
&run transient = 20, cycles = 8 /
&census samples = 2, seed = 3, x_amp = 0.3, v_amp = 1.0 /
&output file = 'run.h5' /
"""


def version_lines(command: list[str]) -> dict[str, str]:
    result = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    facts = dict(line.split(": ", 1) for line in lines[1:])
    return {"first": lines[0], **facts}


def test_version_names_the_blas_and_its_kernel(impactchain_exe):
    facts = version_lines([str(impactchain_exe), "--version"])
    assert facts["first"] == "impactchain 0.1.0"
    assert tuple(k for k in facts if k != "first") == KEYS
    assert all(facts[k] for k in KEYS), facts
    # the BLAS linked by the build is asked at run time: OpenBLAS or BLIS name themselves and
    # the kernels they chose; "unknown" would mean the build lost its BLAS's entry points
    assert facts["blas"].startswith(("OpenBLAS", "BLIS")), facts["blas"]
    assert facts["blas_kernel"] != "unknown"
    assert facts["blas_kernel"] in facts["blas"] or facts["blas"].startswith("BLIS")
    assert facts["compiler"].startswith("GCC"), facts["compiler"]
    # the optimisation level of the build under test (the release profile's, or the one in
    # IMPACTCHAIN_FPM_FLAGS: the runtime-checked build of `make test`)
    flags = os.environ.get("IMPACTCHAIN_FPM_FLAGS") or "-O3"
    level = [f for f in flags.split() if f.startswith("-O")][-1]
    assert level in facts["compiler_options"].split(), facts["compiler_options"]


@pytest.mark.parametrize("text", [RUN, SWEEP, CONTINUATION, CENSUS],
                         ids=["run", "sweep", "continuation", "census"])
def test_every_file_carries_the_provenance(impactchain_exe, tmp_path, text):
    facts = version_lines([str(impactchain_exe), "--version"])
    run_namelist(impactchain_exe, text, tmp_path)
    with h5py.File(tmp_path / "run.h5") as f:
        for key in KEYS:
            value = f.attrs[key]
            value = value.decode() if isinstance(value, bytes) else str(value)
            assert value == facts[key], key


def test_mpi_version_agrees(impactchain_exe, mpi_exe):
    if mpi_exe is None:
        pytest.skip("no MPI build (mpifort not found)")
    ours = version_lines([str(impactchain_exe), "--version"])
    mpi = version_lines(["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", "1",
                         str(mpi_exe), "--version"])
    assert mpi["first"] == "impactchain-mpi 0.1.0"
    assert {k: mpi[k] for k in SHARED} == {k: ours[k] for k in SHARED}


def test_python_provenance_agrees(impactchain_exe):
    from impactchain import api

    if not api.extension_available():
        pytest.skip("the compiled extension is not installed")
    ours = version_lines([str(impactchain_exe), "--version"])
    got = dict(api.provenance())
    assert tuple(got) == KEYS
    assert {k: got[k] for k in SHARED} == {k: ours[k] for k in SHARED}
