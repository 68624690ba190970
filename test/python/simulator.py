"""The built simulator for tests: a fixture with its path, and a runner for namelist texts."""
from __future__ import annotations

import os
import select
import shutil
import subprocess
import time
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



def start_until_progress(exe: Path, args: list[str], cwd: Path, label: str = "cycle",
                         env: dict[str, str] | None = None) -> tuple[subprocess.Popen, str]:
    """Start the simulator with `args` and return once it has shown its first progress line
    of `label` ('cycle': the records, 'point', 'sample'), with the stderr read so far. The run
    is then past its checks and inside that work, whatever the speed of the machine: a test
    that stops it waits for this, not for a guessed time. (IMPACTCHAIN_PROGRESS_AFTER = 0
    shows progress from the first unit; on a pipe the next lines come a tenth apart, so the
    pipe cannot fill.) A run that shows nothing within two minutes fails the test (a hang)."""
    proc = subprocess.Popen([str(exe), *args], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True,
                            env={**(os.environ if env is None else env),
                                 "IMPACTCHAIN_PROGRESS_AFTER": "0"})
    assert proc.stderr is not None
    needle = f"impactchain: {label} ".encode()
    shown = b""
    deadline = time.monotonic() + 120
    while needle not in shown:
        ready, _, _ = select.select([proc.stderr], [], [], max(0.0, deadline - time.monotonic()))
        chunk = os.read(proc.stderr.fileno(), 4096) if ready else b""
        if not chunk:  # ended, or silent for two minutes
            proc.kill()
            out, err = proc.communicate()
            raise AssertionError(f"no '{label}' progress from {args}: "
                                 f"{(shown.decode() + err + out)[-2000:]}")
        shown += chunk
    return proc, shown.decode()


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
