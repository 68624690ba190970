"""Parameter sweeps: identical results with 1 or 2 OpenMP threads and under MPI, a
continuation sweep equal to the same steps run one by one from files, and an interrupted
sweep that resumes to the same file as an uninterrupted one."""
from __future__ import annotations

import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

from simulator import (child_pids, impactchain_exe, mpi_exe,  # noqa: F401 (fixtures)
                       run_namelist, start_until_progress)

GRID = """
&chain n = 6, amplitude = 2.0, omega = 1.5 /
&initial kind = 'random', seed = 3, x_amp = 0.3, v_amp = 0.5 /
&run transient = 50, cycles = 20, record_events = .false. /
&lyapunov vectors = 4 /
&sweep parameter = 'amplitude', start = 1.5, stop = 2.5, step = 0.1, mode = '{mode}',
       parameter2 = 'omega', start2 = 1.3, stop2 = 1.7, step2 = 0.1 /
&output file = '{out}' /
"""


def run_with_threads(exe, tmp_path, text, threads, name):
    (tmp_path / name).write_text(text)
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    result = subprocess.run([str(exe), "--quiet", name], cwd=tmp_path, env=env,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    return result


def assert_same_sweep(a: Path, b: Path) -> None:
    with h5py.File(a) as fa, h5py.File(b) as fb:
        assert sorted(fa["sweep"]) == sorted(fb["sweep"])
        for key in fa["sweep"]:
            np.testing.assert_array_equal(fa["sweep"][key][:], fb["sweep"][key][:], err_msg=key)
        for key in ("parameter", "parameter2", "mode"):
            assert fa["sweep"].attrs[key] == fb["sweep"].attrs[key]


@pytest.mark.parametrize("mode", ["continuation", "independent"])
def test_threads_and_ranks_give_identical_sweeps(impactchain_exe, mpi_exe, tmp_path, mode):
    run_with_threads(impactchain_exe, tmp_path, GRID.format(mode=mode, out="one.h5"), 1,
                     "one.nml")
    run_with_threads(impactchain_exe, tmp_path, GRID.format(mode=mode, out="two.h5"), 2,
                     "two.nml")
    with h5py.File(tmp_path / "one.h5") as f:
        # a 2-D sweep: amplitude (11 values) by omega (5 values)
        np.testing.assert_allclose(f["sweep/point"][:], np.linspace(1.5, 2.5, 11), atol=1e-12)
        np.testing.assert_allclose(f["sweep/point2"][:], np.linspace(1.3, 1.7, 5), atol=1e-12)
        assert f["sweep/x"].shape == (11, 5, 20, 6)
        assert f["sweep/exponents"].shape == (11, 5, 4)
        np.testing.assert_allclose(f["sweep/drive_period"][:],
                                   2 * np.pi / f["sweep/point2"][:], rtol=1e-15)
        assert int(np.ravel(f.attrs["complete"])[0]) == 1
    assert_same_sweep(tmp_path / "one.h5", tmp_path / "two.h5")
    if mpi_exe is None:
        pytest.skip("mpifort is not installed: the MPI comparison needs openmpi")
    (tmp_path / "mpi.nml").write_text(GRID.format(mode=mode, out="mpi.h5"))
    result = subprocess.run(["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", "2",
                             str(mpi_exe), "mpi.nml"], cwd=tmp_path, capture_output=True,
                            text=True, timeout=300, env=dict(os.environ, OMP_NUM_THREADS="1"))
    assert result.returncode == 0, result.stdout + result.stderr
    assert_same_sweep(tmp_path / "one.h5", tmp_path / "mpi.h5")


def test_continuation_equals_runs_from_files(impactchain_exe, tmp_path):
    chain = "&chain n = 8, amplitude = {a}, omega = 1.9, restitution = 0.5 /\n"
    run = "&run transient = 30, cycles = 10, record_events = .false. /\n"
    values = [3.0, 2.9, 2.8, 2.7]
    run_namelist(impactchain_exe, chain.format(a=3.0) + "&initial kind = 'rest' /\n" + run +
                 "&sweep parameter = 'amplitude', start = 3.0, stop = 2.7, step = -0.1 /\n"
                 "&output file = 'sweep.h5' /", tmp_path, "sweep.nml")
    previous = None
    for j, a in enumerate(values):
        start = ("&initial kind = 'rest' /\n" if previous is None else
                 f"&initial kind = 'file', file = '{previous}' /\n")
        run_namelist(impactchain_exe, chain.format(a=a) + start + run +
                     f"&output file = 'step{j}.h5' /", tmp_path, f"step{j}.nml")
        previous = f"step{j}.h5"
    with h5py.File(tmp_path / "sweep.h5") as f:
        np.testing.assert_allclose(f["sweep/point"][:], values, rtol=0, atol=1e-12)
        for j in range(len(values)):
            with h5py.File(tmp_path / f"step{j}.h5") as g:
                np.testing.assert_array_equal(f["sweep/x"][j], g["strobe/x"][:])
                np.testing.assert_array_equal(f["sweep/period"][j], g["strobe/period"][:])


LONG = """
&chain n = 8, amplitude = 6.0, omega = 1.9, damping = 0.05, restitution = 0.5 /
&initial kind = 'rest' /
&run transient = 250, cycles = 50, record_events = .false. /
&sweep parameter = 'amplitude', start = 6.0, stop = 1.0, step = -0.002 /
&output file = '{out}' /
"""


def test_interrupted_sweep_resumes_to_the_same_file(impactchain_exe, tmp_path):
    run_namelist(impactchain_exe, LONG.format(out="whole.h5"), tmp_path, "whole.nml")
    (tmp_path / "part.nml").write_text(LONG.format(out="part.h5"))
    # stopped once a point is done (the first progress line), long before the last
    proc, _ = start_until_progress(impactchain_exe, ["part.nml"], tmp_path, "point")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, err
    assert (tmp_path / "part.h5.ckpt").exists()
    assert not (tmp_path / "part.h5").exists()
    result = run_namelist(impactchain_exe, LONG.format(out="part.h5"), tmp_path, "part.nml")
    resumed = int(result.stdout.split("resumed from a checkpoint: ")[1].split(")")[0])
    assert 0 < resumed < 2501
    assert not (tmp_path / "part.h5.ckpt").exists()
    assert_same_sweep(tmp_path / "whole.h5", tmp_path / "part.h5")


def test_sweep_point_out_of_range_is_refused(impactchain_exe, tmp_path):
    text = ("&chain n = 4, amplitude = 1.0, omega = 1.5 /\n"
            "&sweep parameter = 'restitution', start = 0.8, stop = 1.2, step = 0.1 /\n"
            "&output file = 'bad.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode == 1
    assert "restitution" in result.stderr and "point" in result.stderr
    assert not list(tmp_path.glob("bad.h5*"))


GRID2 = """
&chain n = 8, amplitude = 6.0, omega = 1.9, damping = 0.05, restitution = 0.5 /
&initial kind = 'rest' /
&run transient = 250, cycles = 50 /
&sweep parameter = 'amplitude', start = 6.0, stop = 1.0, step = -0.005,
       parameter2 = 'restitution', start2 = 0.5, stop2 = 0.6, step2 = 0.1 /
&output file = '{out}' /
"""


def test_mpi_sweep_stopped_by_sigterm_resumes(impactchain_exe, mpi_exe, tmp_path):
    """A Slurm-like stop (SIGTERM to every rank) leaves the checkpoint; the same command resumes it
    (also with another number of ranks), and so does the threaded driver: the same checkpoint
    format. Both resumed files equal an uninterrupted run's."""
    if mpi_exe is None:
        pytest.skip("mpifort is not installed: the MPI test needs openmpi")
    run_with_threads(impactchain_exe, tmp_path, GRID2.format(out="whole.h5"), 2, "whole.nml")
    (tmp_path / "part.nml").write_text(GRID2.format(out="part.h5"))
    env = dict(os.environ, OMP_NUM_THREADS="1", IMPACTCHAIN_CHECKPOINT_SECONDS="0.2")
    mpirun = ["mpirun", "--allow-run-as-root", "--oversubscribe"]
    proc = subprocess.Popen([*mpirun, "-np", "2", str(mpi_exe), "part.nml"], cwd=tmp_path,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    ckpt = tmp_path / "part.h5.ckpt"
    deadline = time.monotonic() + 60
    while not ckpt.exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    # like scancel, signal every task (mpirun itself forwards SIGTERM only after a delay)
    ranks = child_pids(proc.pid)
    assert ranks, "no MPI ranks found under mpirun"
    for pid in ranks:
        os.kill(pid, signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode != 0, out + err
    assert "stopped after" in err, out + err
    assert ckpt.exists() and not (tmp_path / "part.h5").exists()
    threaded = tmp_path / "threaded"
    threaded.mkdir()
    shutil.copy(ckpt, threaded / "part.h5.ckpt")
    # the MPI resume, in many short rounds on 3 ranks
    result = subprocess.run([*mpirun, "-np", "3", str(mpi_exe), "part.nml"], cwd=tmp_path,
                            env=env, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stdout + result.stderr
    resumed = int(result.stdout.split("resumed from a checkpoint: ")[1].split(")")[0])
    assert 0 < resumed < 2002
    assert not ckpt.exists()
    assert_same_sweep(tmp_path / "whole.h5", tmp_path / "part.h5")
    # the threaded driver resumes the same checkpoint (same input text, in another directory)
    result = run_namelist(impactchain_exe, GRID2.format(out="part.h5"), threaded, "part.nml")
    assert f"resumed from a checkpoint: {resumed}" in result.stdout
    assert not (threaded / "part.h5.ckpt").exists()
    assert_same_sweep(tmp_path / "whole.h5", threaded / "part.h5")


SMALL = ("&chain n = 4, amplitude = 4.15, omega = 1.5 /\n&run cycles = 10 /\n"
         "&output file = 'out.h5'{output} /\n&sweep parameter = 'amplitude', {sweep} /\n")
# Sweeps refused before anything is allocated or created, by --check as by the run, each
# with one line naming the keys to change: (input, what the message says)
REFUSED = {
    # 5,000,001 points (within the 1e7 of an axis) of 200 records: 32 GB of /sweep/x
    "long axis": ("&chain n = 4, amplitude = 4.15, omega = 1.5 /\n"
                  "&sweep parameter = 'amplitude', start = 1, stop = 6, step = 1e-6 /\n"
                  "&output file = 'out.h5' /\n",
                  "&sweep: the records of this sweep need about 32120.006 MB in the file "
                  "(5000001 points x n x cycles x 8 bytes, plus periods and exponents), more "
                  "than &output max_size_mb = 4096.0000; lower the points (&sweep start, stop, "
                  "step) or &run cycles, or raise max_size_mb"),
    # each axis within 1e7 points, their product not
    "grid": (SMALL.format(output="", sweep="start = 1, stop = 2, step = 1e-4, parameter2 = "
                          "'omega', start2 = 1, stop2 = 2, step2 = 1.25e-4"),
             "&sweep: start, stop, step and start2, stop2, step2 give 10001 x 8001 = "
             "80018001 points; a sweep has at most 1e7"),
    # 100,001 points x 10 records x 4 oscillators x 8 bytes: 32 MB of /sweep/x
    "file over max_size_mb": (SMALL.format(output=", max_size_mb = 1",
                                           sweep="start = 1, stop = 2, step = 1e-5"),
                              "&sweep: the records of this sweep need about 34.400344 MB in "
                              "the file (100001 points"),
    # the file fits (0.34 MB), the records and a checkpoint's copy of them in memory not
    "memory over max_size_mb": (SMALL.format(output=", max_size_mb = 0.5",
                                             sweep="start = 1, stop = 2, step = 1e-3"),
                                "&sweep: this sweep needs about 0.74086000 MB of memory"),
    "missing directory": (SMALL.format(output="", sweep="start = 1, stop = 2, step = 0.5")
                          .replace("'out.h5'", "'nodir/out.h5'"),
                          "&output: cannot create 'nodir/out.h5': the directory 'nodir' does "
                          "not exist"),
    # within a raised max_size_mb (about 24 GB), but 3e9 values in the one branch
    "branch beyond 2**31 values": ("&chain n = 100, amplitude = 1.7, omega = 1.5 /\n"
                                   "&run cycles = 1000000 /\n&output file = 'out.h5', "
                                   "max_size_mb = 1e9 /\n&sweep parameter = 'amplitude', "
                                   "start = 1, stop = 1.29, step = 0.01 /\n",
                                   "&sweep: a branch of this sweep holds about"),
    "max_size_mb = 0": (SMALL.format(output=", max_size_mb = 0",
                                     sweep="start = 1, stop = 2, step = 0.5"),
                        "&output: max_size_mb = 0.0000000 is outside (0, 1e9]"),
}


# (under MPI, one case of each kind of check, the sizes and the output, as every rank runs
# the same procedure the threaded driver does: each mpirun costs seconds of CI)
@pytest.mark.parametrize("case, driver", [(case, "threads") for case in sorted(REFUSED)] +
                         [("memory over max_size_mb", "mpi"), ("missing directory", "mpi")])
def test_sweep_refused_before_anything_exists(impactchain_exe, mpi_exe, tmp_path, case,
                                              driver):
    """Exit status 1, one line naming the keys, no backtrace, and nothing written (no file,
    no .part, no checkpoint), from --check and from the run, threaded and under MPI."""
    if driver == "mpi" and mpi_exe is None:
        pytest.skip("mpifort is not installed: the MPI test needs openmpi")
    text, message = REFUSED[case]
    (tmp_path / "in.nml").write_text(text)
    command = [str(impactchain_exe)]
    if driver == "mpi":
        command = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", "2",
                   str(mpi_exe)]
    for check in (["--check"], []):
        result = subprocess.run([*command, "--quiet", *check, "in.nml"], cwd=tmp_path,
                                capture_output=True, text=True, timeout=120,
                                env=dict(os.environ, OMP_NUM_THREADS="1"))
        assert result.returncode == 1, (check, result.stdout, result.stderr)
        program = "impactchain-mpi" if driver == "mpi" else "impactchain"
        errors = [line for line in result.stderr.splitlines() if line.startswith(program)]
        assert len(errors) == 1 and errors[0].startswith(f"{program}: error: {message}"), \
            (check, result.stderr)
        if driver == "threads":
            assert result.stderr == errors[0] + "\n"
        assert "Backtrace" not in result.stderr and not result.stdout
        assert sorted(p.name for p in tmp_path.iterdir()) == ["in.nml"], check


def test_check_refuses_an_existing_sweep_output(impactchain_exe, tmp_path):
    """--check refuses an output the sweep would refuse (it exists, no --overwrite), and
    passes it with --overwrite; neither touches it."""
    (tmp_path / "in.nml").write_text(SMALL.format(output="", sweep="start = 1, stop = 2, "
                                                                   "step = 0.5"))
    (tmp_path / "out.h5").write_bytes(b"precious")
    for check in (["--check"], []):
        result = subprocess.run([str(impactchain_exe), "--quiet", *check, "in.nml"],
                                cwd=tmp_path, capture_output=True, text=True, timeout=120)
        assert result.returncode == 1, result.stderr
        assert result.stderr == ("impactchain: error: &output: file = 'out.h5' exists; "
                                 "choose another name or set overwrite = .true.\n")
    result = subprocess.run([str(impactchain_exe), "--check", "--overwrite", "in.nml"],
                            cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0 and "&sweep" in result.stdout, result.stderr
    assert (tmp_path / "out.h5").read_bytes() == b"precious"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.nml", "out.h5"]


def test_mpi_sweep_stops_when_its_checkpoint_cannot_be_written(mpi_exe, tmp_path):
    """Issue 30, 2: under MPI a checkpoint that cannot be written (its temporary file's name
    is taken by a directory) stops every rank with the error, exit 1; before, it was a
    warning and the sweep went on without a checkpoint."""
    if mpi_exe is None:
        pytest.skip("mpifort is not installed: the MPI test needs openmpi")
    (tmp_path / "part.nml").write_text(GRID2.format(out="part.h5"))
    (tmp_path / "part.h5.ckpt.tmp").mkdir()
    env = dict(os.environ, OMP_NUM_THREADS="1", IMPACTCHAIN_CHECKPOINT_SECONDS="0.2")
    result = subprocess.run(["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", "2",
                             str(mpi_exe), "--quiet", "part.nml"], cwd=tmp_path, env=env,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 1, result.stderr
    assert "cannot write the checkpoint" in result.stderr, result.stderr
    assert "warning" not in result.stderr
    assert not (tmp_path / "part.h5").exists() and not (tmp_path / "part.h5.part").exists()
