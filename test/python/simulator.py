"""The built simulator for tests: a fixture with its path, and a runner for namelist texts."""
from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FPM = ROOT / ".venv" / "bin" / "fpm"


@pytest.fixture(scope="session")
def impactchain_exe() -> Path:
    """Path of the simulator (built if needed): the release build, or the build with the
    compiler flags in IMPACTCHAIN_FPM_FLAGS (e.g. gfortran's runtime checks)."""
    flags = os.environ.get("IMPACTCHAIN_FPM_FLAGS")
    profile = ["--flag", flags] if flags else ["--profile", "release"]
    out = subprocess.run(
        [str(FPM), "run", *profile, "--runner", "echo"],
        cwd=ROOT, capture_output=True, text=True, check=True,
    )
    path = ROOT / out.stdout.strip().splitlines()[-1]
    assert path.exists(), out.stdout + out.stderr
    return path



def run_namelist(exe: Path, text: str, workdir: Path, name: str = "input.nml",
                 check: bool = True) -> subprocess.CompletedProcess:
    """Write `text` as a namelist in `workdir` and run the simulator on it there."""
    (workdir / name).write_text(text)
    result = subprocess.run([str(exe), "--quiet", name], cwd=workdir,
                            capture_output=True, text=True, timeout=120)
    if check and result.returncode != 0:
        raise AssertionError(f"impactchain failed: {result.stderr}")
    return result


@pytest.fixture(scope="session")
def mpi_exe() -> Path | None:
    """The MPI build of the sweep and census driver (mpi/), or None when mpifort is not
    installed."""
    if shutil.which("mpifort") is None:
        return None
    flags = os.environ.get("IMPACTCHAIN_FPM_FLAGS")   # the same build as impactchain_exe
    profile = ["--flag", flags] if flags else ["--profile", "release"]
    out = subprocess.run([str(FPM), "run", *profile, "--compiler", "mpifort",
                          "--runner", "echo"], cwd=ROOT / "mpi", capture_output=True,
                         text=True, check=True)
    return ROOT / "mpi" / out.stdout.strip().splitlines()[-1]


def child_pids(pid: int) -> list[int]:
    """Processes whose parent is pid (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
    return found
