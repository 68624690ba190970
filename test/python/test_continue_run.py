"""A single run stopped by SIGINT/SIGTERM records planned and done cycles, and the same command
continues it into the same file, bit for bit the file of an uninterrupted run (every dataset
and attribute, with Lyapunov exponents, finite-time exponents, events and the Jacobian on),
even when stopped twice.
A finished file is still refused without overwrite, and a stopped run of another input is
refused with a message saying so; neither is touched."""
from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import h5py
import numpy as np

from simulator import impactchain_exe, run_namelist  # noqa: F401 (fixture)

CYCLES = 100000
INPUT = f"""&chain n = 16, amplitude = 1.7, omega = 1.5 /
&initial kind = 'random', seed = 4, x_amp = 0.3, v_amp = 0.4 /
&run transient = 20, cycles = {CYCLES}, max_period = 4 /
&lyapunov vectors = 6, qr_every = 2, jacobian = .true., window = 10 /
&output file = 'run.h5' /
"""


def _contents(path: Path) -> dict[str, object]:
    """Every dataset (values and type) and attribute of a file, by path; the dimension
    scales' references (object addresses, which differ between two files of the same
    content) as the names of the objects they refer to."""
    out: dict[str, object] = {}
    with h5py.File(path) as f:
        for name, value in f.attrs.items():
            out[f"@{name}"] = value

        def visit(name: str, obj: object) -> None:
            if isinstance(obj, h5py.Dataset):
                out[name] = (obj.dtype.str, obj[()])
            for key, value in obj.attrs.items():
                if key == "DIMENSION_LIST":
                    value = [[f[ref].name for ref in axis] for axis in value]
                elif key == "REFERENCE_LIST":
                    value = sorted((f[ref].name, int(axis)) for ref, axis in value)
                out[f"{name}@{key}"] = value

        f.visititems(visit)
    return out


def _same(a: object, b: object) -> bool:
    if isinstance(a, tuple):
        return a[0] == b[0] and _same(a[1], b[1])
    a, b = np.asarray(a), np.asarray(b)
    return a.dtype == b.dtype and a.shape == b.shape and bool(
        np.array_equal(a, b, equal_nan=a.dtype.kind == "f"))


def _stop_early(exe: Path, workdir: Path, sig: int) -> None:
    """Run INPUT in workdir and stop it with `sig` once it has written some records."""
    proc = subprocess.Popen([str(exe), "--quiet", "run.nml"], cwd=workdir,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    part = workdir / "run.h5.part"
    start_size = None
    deadline = time.time() + 60
    # wait for a few chunks of events to reach the file (the run has then done thousands of
    # its 10^5 records, and is far from its end)
    while time.time() < deadline and proc.poll() is None:
        if part.exists():
            size = part.stat().st_size
            start_size = size if start_size is None else start_size
            if size > start_size + 3_000_000:
                break
        time.sleep(0.01)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, err
    assert "run the same command again to continue it" in err


def test_stopped_run_continues_bit_for_bit(impactchain_exe, tmp_path):
    whole, parts = tmp_path / "whole", tmp_path / "parts"
    whole.mkdir()
    parts.mkdir()
    run_namelist(impactchain_exe, INPUT, whole, "run.nml")

    (parts / "run.nml").write_text(INPUT)
    _stop_early(impactchain_exe, parts, signal.SIGINT)
    with h5py.File(parts / "run.h5") as f:
        assert int(np.ravel(f.attrs["complete"])[0]) == 0
        done = int(f["stats/cycles_done"][()])
        assert 0 < done < CYCLES
        assert int(np.ravel(f["params"].attrs["cycles"])[0]) == CYCLES
        assert f["strobe/x"].shape == (done, 16) and "resume" in f
        # the finite-time exponents of the windows done, and no more
        windows = f["finite_time/exponents"]
        assert windows.shape == (done // 10, 6) and done >= 10
        assert np.all(np.isfinite(windows[()]))
    assert not (parts / "run.h5.part").exists()

    # a stopped run of another input is not continued, and left as it was
    stopped = (parts / "run.h5").read_bytes()
    other = run_namelist(impactchain_exe, INPUT.replace("seed = 4", "seed = 5"), parts,
                         "other.nml", check=False)
    assert other.returncode == 1
    assert "is a run stopped early from another input" in other.stderr, other.stderr
    assert "overwrite = .true." in other.stderr
    # --check answers as the runs do: the same input passes (it continues the file), the
    # other is refused with the same line
    check = subprocess.run([str(impactchain_exe), "--check", "run.nml"], cwd=parts,
                           capture_output=True, text=True, timeout=60)
    assert check.returncode == 0, check.stderr
    check = subprocess.run([str(impactchain_exe), "--check", "other.nml"], cwd=parts,
                           capture_output=True, text=True, timeout=60)
    assert check.returncode == 1 and check.stderr == other.stderr
    assert (parts / "run.h5").read_bytes() == stopped
    assert not (parts / "run.h5.part").exists()

    # the same command continues it; stopped a second time, then once more to the end
    _stop_early(impactchain_exe, parts, signal.SIGTERM)
    with h5py.File(parts / "run.h5") as f:
        assert done < int(f["stats/cycles_done"][()]) < CYCLES
    result = run_namelist(impactchain_exe, INPUT, parts, "run.nml")
    assert "continued a run stopped early after" in result.stdout

    a, b = _contents(whole / "run.h5"), _contents(parts / "run.h5")
    assert sorted(a) == sorted(b)
    for name in ("events/time", "lyapunov/running", "floquet/jacobian", "stats/cycles_done",
                 "finite_time/exponents"):
        assert name in a
    different = [name for name in a if not _same(a[name], b[name])]
    assert not different, different

    # a finished file is refused, as before
    finished = (parts / "run.h5").read_bytes()
    again = run_namelist(impactchain_exe, INPUT, parts, "run.nml", check=False)
    assert again.returncode == 1 and "exists" in again.stderr
    assert (parts / "run.h5").read_bytes() == finished


# A run long enough (a few seconds) for a second process to start while it writes.
CONCURRENT = """&chain n = 16, amplitude = 1.7, omega = 1.5 /
&initial kind = 'random', seed = 1, x_amp = 0.3, v_amp = 0.3 /
&run transient = 0, cycles = 60000 /
&output file = 'o.h5' /
"""


def _wait_for_records(proc: subprocess.Popen, part: Path) -> None:
    """Wait until `proc` has written records into `part` (the file has grown)."""
    deadline = time.time() + 60
    while time.time() < deadline and proc.poll() is None:
        if part.exists() and part.stat().st_size > 200_000:
            return
        time.sleep(0.01)
    raise AssertionError("the first run wrote nothing: " + proc.communicate()[1])


def test_second_run_on_one_output_is_refused_and_the_first_ends_intact(impactchain_exe,
                                                                       tmp_path):
    """Issue 30, 1: the second of two processes on one output (with or without --overwrite,
    and the same input or another) is refused before it touches `NAME.h5.part`, saying that
    another run is writing it; the first ends with the file an undisturbed run writes."""
    alone = tmp_path / "alone"
    alone.mkdir()
    run_namelist(impactchain_exe, CONCURRENT, alone, "a.nml")
    (tmp_path / "a.nml").write_text(CONCURRENT)
    (tmp_path / "b.nml").write_text(CONCURRENT.replace("seed = 1", "seed = 2"))
    first = subprocess.Popen([str(impactchain_exe), "--quiet", "a.nml"], cwd=tmp_path,
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    part = tmp_path / "o.h5.part"
    _wait_for_records(first, part)
    for command in (["a.nml"], ["--overwrite", "a.nml"], ["--overwrite", "b.nml"],
                    ["--check", "--overwrite", "a.nml"]):
        size = part.stat().st_size
        second = subprocess.run([str(impactchain_exe), "--quiet", *command], cwd=tmp_path,
                                capture_output=True, text=True, timeout=60)
        assert second.returncode == 1, (command, second.stderr)
        assert "another run is writing 'o.h5.part'" in second.stderr, second.stderr
        assert part.stat().st_size >= size, command  # not truncated
    out, err = first.communicate(timeout=120)
    assert first.returncode == 0, err
    assert not part.exists()
    a, b = _contents(alone / "o.h5"), _contents(tmp_path / "o.h5")
    assert sorted(a) == sorted(b)
    assert not [name for name in a if not _same(a[name], b[name])]


def test_overwrite_continues_a_stopped_run(impactchain_exe, tmp_path):
    """Issue 30, 5: whether a file may be replaced is not part of the input: a run stopped
    early continues when the command adds --overwrite (or drops it), as the same command
    does, to the file of an undisturbed run."""
    alone = tmp_path / "alone"
    alone.mkdir()
    run_namelist(impactchain_exe, CONCURRENT, alone, "a.nml")
    (tmp_path / "a.nml").write_text(CONCURRENT)
    for first, then in (([], ["--overwrite"]), (["--overwrite"], [])):
        (tmp_path / "o.h5").unlink(missing_ok=True)
        proc = subprocess.Popen([str(impactchain_exe), "--quiet", *first, "a.nml"],
                                cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True)
        _wait_for_records(proc, tmp_path / "o.h5.part")
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
        assert proc.returncode == 3, err
        result = subprocess.run([str(impactchain_exe), "--quiet", *then, "a.nml"],
                                cwd=tmp_path, capture_output=True, text=True, timeout=120)
        assert result.returncode == 0, result.stderr
        assert "continued a run stopped early after" in result.stdout, (first, then)
        if not first:
            a, b = _contents(alone / "o.h5"), _contents(tmp_path / "o.h5")
            assert sorted(a) == sorted(b)
            assert not [name for name in a if not _same(a[name], b[name])]


def test_killed_run_continues_from_its_last_checkpoint_bit_for_bit(impactchain_exe, tmp_path):
    """Issue 30, 3: a run killed (SIGKILL: the OOM killer, a scheduler's hard limit) keeps
    the records of its last checkpoint under the final name, marked complete = 0, and the
    same command continues from there to the file of an uninterrupted run, bit for bit
    (exponents, finite-time exponents, events and the Jacobian on). Checkpoints come every
    IMPACTCHAIN_CHECKPOINT_SECONDS seconds (here 0: as often as their cost allows, the first
    at the first record); a run that makes them, uninterrupted, writes the same file too. Before, the `.part` file of a killed
    run was all there was (unreadable), and the rerun started at cycle 0."""
    whole, saved, killed = (tmp_path / name for name in ("whole", "saved", "killed"))
    for folder in (whole, saved, killed):
        folder.mkdir()
        (folder / "run.nml").write_text(INPUT)
    env = {**os.environ, "IMPACTCHAIN_CHECKPOINT_SECONDS": "1e6"}
    subprocess.run([str(impactchain_exe), "--quiet", "run.nml"], cwd=whole, env=env,
                   check=True, capture_output=True, timeout=300)
    env["IMPACTCHAIN_CHECKPOINT_SECONDS"] = "0"
    subprocess.run([str(impactchain_exe), "--quiet", "run.nml"], cwd=saved, env=env,
                   check=True, capture_output=True, timeout=300)

    proc = subprocess.Popen([str(impactchain_exe), "--quiet", "run.nml"], cwd=killed, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.time() + 120
    # killed once its first checkpoint is under the final name (with 0 seconds between them,
    # at its first record; the whole run takes seconds more, on any machine)
    while time.time() < deadline and proc.poll() is None:
        if (killed / "run.h5").exists():
            break
        time.sleep(0.002)
    proc.kill()
    proc.communicate()
    assert proc.returncode == -signal.SIGKILL, "the run ended before it could be killed"
    with h5py.File(killed / "run.h5") as f:
        assert int(np.ravel(f.attrs["complete"])[0]) == 0
        done = int(f["stats/cycles_done"][()])
        assert 0 < done < CYCLES and "resume" in f
    result = run_namelist(impactchain_exe, INPUT, killed, "run.nml")
    assert f"continued a run stopped early after {done} records" in result.stdout

    a = _contents(whole / "run.h5")
    for other in (saved, killed):
        b = _contents(other / "run.h5")
        assert sorted(a) == sorted(b)
        different = [name for name in a if not _same(a[name], b[name])]
        assert not different, (other.name, different)
        assert not (other / "run.h5.part").exists()
        assert not (other / "run.h5.saving").exists()


def test_checkpoint_interval_from_the_environment_is_checked(impactchain_exe, tmp_path):
    """IMPACTCHAIN_CHECKPOINT_SECONDS must be a number of seconds; anything else is refused
    before the run starts, naming the variable and its range."""
    (tmp_path / "run.nml").write_text(INPUT)
    for bad in ("soon", "-1", "nan", "1e400"):
        result = subprocess.run([str(impactchain_exe), "--quiet", "run.nml"], cwd=tmp_path,
                                env={**os.environ, "IMPACTCHAIN_CHECKPOINT_SECONDS": bad},
                                capture_output=True, text=True, timeout=60)
        assert result.returncode == 1, bad
        assert (f"IMPACTCHAIN_CHECKPOINT_SECONDS = {bad} is not a number of seconds in "
                "[0, 1e6]") in result.stderr, result.stderr
        assert not list(tmp_path.glob("run.h5*"))
