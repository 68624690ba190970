"""The simulator's command line: output layout, refusals of bad input with a message naming
the key and a non-zero exit and no output file, overwrite protection, and bit-identical
continuation from a file."""
from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest

from simulator import (ROOT, impactchain_exe, mpi_exe, run_namelist,  # noqa: F401 (fixtures)
                       start_until_progress)

BASE = """
&chain n = 6, amplitude = 1.7, omega = 1.5 /
&initial kind = 'random', seed = 3, x_amp = 0.3, v_amp = 0.3 /
&run transient = 10, cycles = 20 /
&output file = 'run.h5' /
"""


def test_output_layout(impactchain_exe, tmp_path):
    result = run_namelist(impactchain_exe, BASE, tmp_path)
    assert "collisions per cycle" in result.stdout
    with h5py.File(tmp_path / "run.h5") as f:
        assert f.attrs["schema_version"] == 2
        assert int(np.ravel(f.attrs["complete"])[0]) == 1
        assert "&chain" in f.attrs["input_namelist"].decode() if isinstance(
            f.attrs["input_namelist"], bytes) else "&chain" in str(f.attrs["input_namelist"])
        assert f["strobe/x"].shape == (20, 6)
        assert f["strobe/v"].shape == (20, 6)
        np.testing.assert_array_equal(f["strobe/cycle"][:], np.arange(11, 31))
        assert f["params/spacing"].shape == (7,)
        assert f["initial/x"].shape == (6,)
        assert f["final/x"].shape == (6,)
        assert f["strobe/period"].shape == (6,)
        sites = f["events/site"][:]
        assert sites.min() >= 0 and sites.max() <= 6
        assert np.all(f["events/speed"][:] >= 0)
        times = f["events/time"][:]
        period = 2 * np.pi / 1.5
        assert np.all(np.diff(times) >= 0)
        assert times[0] >= 10 * period and times[-1] <= 30 * period
        assert f["stats/site_counts"][:].sum() == int(np.ravel(f["stats"].attrs["impacts"])[0])
    assert not (tmp_path / "run.h5.part").exists()


BAD_INPUTS = {
    "damping = 1.2": ("&chain n=4, amplitude=1, omega=1.5, damping=1.2 /", "damping"),
    "negative damping": ("&chain n=4, amplitude=1, omega=1.5, damping=-0.1 /", "damping"),
    "restitution > 1": ("&chain n=4, amplitude=1, omega=1.5, restitution=1.3 /", "restitution"),
    "n = 0": ("&chain n=0, amplitude=1, omega=1.5 /", "n = 0"),
    "missing n": ("&chain amplitude=1, omega=1.5 /", "n (number"),
    "missing amplitude": ("&chain n=4, omega=1.5 /", "amplitude"),
    "omega = 0": ("&chain n=4, amplitude=1, omega=0 /", "omega"),
    "NaN spacing": ("&chain n=4, amplitude=1, omega=1.5, spacing=NaN /", "spacing"),
    "wrong spacing count": ("&chain n=4, amplitude=1, omega=1.5, spacing=1,1,1 /", "spacing"),
    "boundary": ("&chain n=4, amplitude=1, omega=1.5, boundary='open' /", "boundary"),
    "misspelt key": ("&chain n=4, amplitude=1, omega=1.5, dampin=0.1 /", "&chain"),
    "unknown group": ("&chain n=4, amplitude=1, omega=1.5 /\n&chian n=3 /", "&chian"),
    "duplicate group": ("&chain n=4, amplitude=1, omega=1.5 /\n&chain n=3 /", "more than once"),
    "no chain": ("&run cycles=3 /", "&chain"),
    "resonance": ("&chain n=4, amplitude=1, omega=1, damping=0 /", "resonance"),
    "initial kind": ("&chain n=4, amplitude=1, omega=1.5 /\n&initial kind='zero' /", "kind"),
    "overlap": ("&chain n=2, amplitude=1, omega=1.5 /\n&initial kind='explicit', "
                "x0=0.8,-0.8 /", "bond 1"),
    "explicit count": ("&chain n=3, amplitude=1, omega=1.5 /\n&initial kind='explicit', "
                       "x0=0.1 /", "x0"),
    "x_amp too big": ("&chain n=3, amplitude=1, omega=1.5 /\n&initial kind='random', "
                      "x_amp=0.7 /", "x_amp"),
    "cycles": ("&chain n=3, amplitude=1, omega=1.5 /\n&run cycles=0 /", "cycles"),
    "phase": ("&chain n=3, amplitude=1, omega=1.5 /\n&run phase=7 /", "phase"),
    "vectors": ("&chain n=3, amplitude=1, omega=1.5 /\n&lyapunov vectors=7 /", "vectors"),
    "missing file start": ("&chain n=3, amplitude=1, omega=1.5 /\n&initial kind='file', "
                           "file='nothere.h5' /", "nothere.h5"),
    "truncated group": ("&chain n=3, amplitude=1, omega=1.5", "&chain"),
    "size limit": ("&chain n=1000, amplitude=1, omega=1.5 /\n&run cycles=1000000 /\n"
                   "&output max_size_mb=10 /", "max_size_mb"),
    "size limit zero": ("&chain n=3, amplitude=1, omega=1.5 /\n&output max_size_mb=0 /",
                        "&output: max_size_mb = 0.0000000 is outside (0, 1e9]"),
}


@pytest.mark.parametrize("case", sorted(BAD_INPUTS))
def test_bad_input_is_refused(impactchain_exe, tmp_path, case):
    text, needle = BAD_INPUTS[case]
    text += "\n&output file='bad.h5' /\n" if "&output" not in text else ""
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode != 0
    assert "impactchain: error:" in result.stderr
    assert needle in result.stderr, result.stderr
    assert "Backtrace" not in result.stderr
    assert not list(tmp_path.glob("*.h5*")), "no output may be left behind"


def test_mpi_driver_exit_codes(mpi_exe, tmp_path):
    if mpi_exe is None:
        pytest.skip("no MPI build (mpifort not found)")
    mpirun = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", "2", str(mpi_exe)]
    for args, code, out in [(["--help"], 0, "usage: impactchain-mpi"),
                            (["--bogus", "x.nml"], 2, "")]:
        result = subprocess.run([*mpirun, *args], cwd=tmp_path, capture_output=True, text=True,
                                timeout=120)
        assert result.returncode == code, (args, result.stdout, result.stderr)
        assert out in result.stdout


def test_existing_output_is_not_overwritten(impactchain_exe, tmp_path):
    (tmp_path / "run.h5").write_bytes(b"precious")
    result = run_namelist(impactchain_exe, BASE, tmp_path, check=False)
    assert result.returncode != 0
    assert "exists" in result.stderr
    assert (tmp_path / "run.h5").read_bytes() == b"precious"
    run_namelist(impactchain_exe, BASE.replace("'run.h5' /", "'run.h5', overwrite=.true. /"),
                 tmp_path)
    assert h5py.is_hdf5(tmp_path / "run.h5")


def test_unwritable_output_directory_is_refused(impactchain_exe, tmp_path):
    result = run_namelist(impactchain_exe, BASE.replace("'run.h5'", "'missing/dir/run.h5'"),
                          tmp_path, check=False)
    assert result.returncode != 0
    assert "cannot create" in result.stderr


def test_nothing_the_user_owns_is_replaced(impactchain_exe, tmp_path):
    """Issue 30, 7: the input file given as the output (even with --overwrite), a user's
    own NAME.h5.part, a symbolic link at NAME.h5.part and a dangling symbolic link at the
    output's name (unless --overwrite) are refused, and left as they were."""
    (tmp_path / "in.nml").write_text(BASE)
    result = subprocess.run([str(impactchain_exe), "--quiet", "-o", "./in.nml", "--overwrite",
                             "in.nml"], cwd=tmp_path, capture_output=True, text=True,
                            timeout=60)
    assert result.returncode == 1
    assert "&output: file = './in.nml' is the input file" in result.stderr, result.stderr
    assert (tmp_path / "in.nml").read_text() == BASE

    (tmp_path / "run.h5.part").write_text("my notes")
    for args in ([], ["--overwrite"], ["--check"]):
        result = subprocess.run([str(impactchain_exe), "--quiet", *args, "in.nml"],
                                cwd=tmp_path, capture_output=True, text=True, timeout=60)
        assert result.returncode == 1, args
        assert "'run.h5.part' exists and is not a file a run left" in result.stderr, \
            result.stderr
        assert (tmp_path / "run.h5.part").read_text() == "my notes"
    (tmp_path / "run.h5.part").unlink()

    (tmp_path / "run.h5.part").symlink_to(tmp_path / "elsewhere")
    result = run_namelist(impactchain_exe, BASE, tmp_path, check=False)
    assert result.returncode == 1 and "is a symbolic link" in result.stderr, result.stderr
    assert not (tmp_path / "elsewhere").exists()
    (tmp_path / "run.h5.part").unlink()

    (tmp_path / "run.h5").symlink_to(tmp_path / "missing.h5")
    result = run_namelist(impactchain_exe, BASE, tmp_path, check=False)
    assert result.returncode == 1 and "'run.h5' exists" in result.stderr, result.stderr
    assert (tmp_path / "run.h5").is_symlink()
    run_namelist(impactchain_exe, BASE.replace("'run.h5' /", "'run.h5', overwrite=.true. /"),
                 tmp_path)
    assert not (tmp_path / "run.h5").is_symlink() and h5py.is_hdf5(tmp_path / "run.h5")

    # a .part left by a killed run (HDF5, or empty) is replaced without a word
    (tmp_path / "run.h5").unlink()
    (tmp_path / "run.h5.part").write_bytes(b"")
    run_namelist(impactchain_exe, BASE, tmp_path)
    assert h5py.is_hdf5(tmp_path / "run.h5") and not (tmp_path / "run.h5.part").exists()


def test_finished_file_is_renamed_durably(impactchain_exe, tmp_path):
    """Issue 30: the finished file is flushed to the disk before it takes its name, and the
    directory after (fsync of the file, then of the directory: seen with strace). Before,
    neither was flushed. (Checkpoints are renamed by the same function, chain_files'
    rename_file.)"""
    import shutil
    if shutil.which("strace") is None:
        pytest.skip("strace is not installed")
    (tmp_path / "input.nml").write_text(BASE)
    result = subprocess.run(["strace", "-f", "-e", "trace=openat,fsync,rename", "-o", "trace",
                             str(impactchain_exe), "--quiet", "input.nml"], cwd=tmp_path,
                            capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr
    calls = [line.split(None, 1)[1] for line in (tmp_path / "trace").read_text().splitlines()]
    renamed = next(j for j, c in enumerate(calls) if c.startswith('rename("run.h5.part"'))
    assert calls[renamed - 1].startswith("fsync(") and " = 0" in calls[renamed - 1]
    assert 'openat(AT_FDCWD, "run.h5.part", O_RDONLY' in calls[renamed - 2]
    assert "O_DIRECTORY" in calls[renamed + 1]
    assert calls[renamed + 2].startswith("fsync(") and " = 0" in calls[renamed + 2]


@pytest.mark.parametrize("kind", ["run", "sweep"])
def test_output_that_is_a_directory_is_refused_up_front(impactchain_exe, tmp_path, kind):
    """Issue 30, 6: an output path that is a directory is refused by --check and by the run
    itself before anything is computed, even with --overwrite (which never replaces a
    directory)."""
    (tmp_path / "run.h5").mkdir()
    text = BASE
    if kind == "sweep":
        text += "&sweep parameter = 'amplitude', start = 1.5, stop = 2.5, step = 0.5 /\n"
    (tmp_path / "input.nml").write_text(text)
    for args in (["--check", "--overwrite"], ["--overwrite"], []):
        result = subprocess.run([str(impactchain_exe), "--quiet", *args, "input.nml"],
                                cwd=tmp_path, capture_output=True, text=True, timeout=60)
        assert result.returncode == 1, (args, result.stderr)
        assert "&output: file = 'run.h5' is a directory" in result.stderr, result.stderr
        assert (tmp_path / "run.h5").is_dir()
        assert not (tmp_path / "run.h5.part").exists()


@pytest.mark.parametrize("phase", [0.0, 1.1])
def test_continuation_is_bit_identical(impactchain_exe, tmp_path, phase):
    chain = "&chain n = 8, amplitude = 1.7, omega = 1.5 /\n"
    start = "&initial kind = 'random', seed = 5, x_amp = 0.3, v_amp = 0.5 /\n"
    run_namelist(impactchain_exe, chain + start +
                 f"&run transient = 5, cycles = 30, phase = {phase} /\n&output file = 'a.h5' /",
                 tmp_path, "a.nml")
    run_namelist(impactchain_exe, chain + start +
                 f"&run transient = 5, cycles = 12, phase = {phase} /\n&output file = 'b.h5' /",
                 tmp_path, "b.nml")
    run_namelist(impactchain_exe, chain + "&initial kind = 'file', file = 'b.h5' /\n" +
                 f"&run transient = 0, cycles = 18, phase = {phase} /\n&output file = 'c.h5' /",
                 tmp_path, "c.nml")
    with h5py.File(tmp_path / "a.h5") as a, h5py.File(tmp_path / "c.h5") as c:
        np.testing.assert_array_equal(a["strobe/x"][12:], c["strobe/x"][:])
        np.testing.assert_array_equal(a["strobe/v"][12:], c["strobe/v"][:])
        np.testing.assert_array_equal(a["strobe/cycle"][12:], c["strobe/cycle"][:])
        np.testing.assert_array_equal(a["final/x"][:], c["final/x"][:])
        n_c = len(c["events/time"])
        np.testing.assert_array_equal(a["events/site"][-n_c:], c["events/site"][:])
        period = 2 * np.pi / 1.5
        np.testing.assert_allclose(a["events/time"][-n_c:] - 17 * period - phase / 1.5,
                                   c["events/time"][:],
                                   rtol=0, atol=1e-9)


LONG = """
&chain n = 16, amplitude = 1.7, omega = 1.5 /
&initial kind = 'random', x_amp = 0.3, v_amp = 0.3 /
&run cycles = 50000000 /
&output file = 'long.h5', max_size_mb = 1e6 /
"""


def _start_long_run(exe, tmp_path):
    """The long run, once it has recorded its first cycle (on any machine)."""
    (tmp_path / "long.nml").write_text(LONG)
    proc, _ = start_until_progress(exe, ["long.nml"], tmp_path)
    return proc


@pytest.mark.parametrize("signal_name", ["SIGINT", "SIGTERM"])
def test_interrupt_keeps_finished_records(impactchain_exe, tmp_path, signal_name):
    import signal
    proc = _start_long_run(impactchain_exe, tmp_path)
    proc.send_signal(getattr(signal, signal_name))
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 3, err
    assert "stopped early" in err
    with h5py.File(tmp_path / "long.h5") as f:
        assert int(np.ravel(f.attrs["complete"])[0]) == 0
        cycles = f["strobe/cycle"][:]
        assert len(cycles) > 0 and f["strobe/x"].shape == (len(cycles), 16)
        np.testing.assert_array_equal(cycles, np.arange(1, len(cycles) + 1))
        assert "final" in f
    assert not (tmp_path / "long.h5.part").exists()


def test_killed_run_leaves_no_file_that_claims_completion(impactchain_exe, tmp_path):
    proc = _start_long_run(impactchain_exe, tmp_path)
    proc.kill()
    proc.communicate(timeout=60)
    assert not (tmp_path / "long.h5").exists()
    assert (tmp_path / "long.h5.part").exists()


@pytest.mark.parametrize("args, code, says", [
    (["--version"], 0, "impactchain 0.1.0"),
    (["--help"], 0, "usage: impactchain"),
    ([], 2, "usage: impactchain"),
    (["--bogus", "run.nml"], 2, "unknown option '--bogus'"),
    (["a.nml", "b.nml"], 2, "give one input file, not 'a.nml' and 'b.nml'"),
    (["--set"], 2, "--set needs a value"),
    (["missing.nml"], 1, "missing.nml"),   # bad input, not a mistake in the command line
])
def test_command_line(impactchain_exe, tmp_path, args, code, says):
    """The command line (chain_cli, shared with the MPI driver): options, exit codes, words."""
    result = subprocess.run([str(impactchain_exe), *args], cwd=tmp_path, capture_output=True,
                            text=True, timeout=60)
    assert result.returncode == code
    assert says in result.stdout + result.stderr
    assert not list(tmp_path.iterdir())


RESOLVED_CASES = {
    "explicit start, spacing list": """
&chain n = 3, spacing = 1.0, 0.7, 1.3, 0.9, amplitude = 2.1, omega = 1.3, damping = 0.1 /
&initial kind = 'explicit', x0 = 0.1, -0.2, 0.3, v0 = 0.05, 0.0, -0.1 /
&run transient = 5, cycles = 12, phase = 0.3, stick_speed = 1e-8 /
&lyapunov enabled = .true., qr_every = 2 /
&output file = 'run.h5' /
""",
    "random start": BASE,
    "two-parameter sweep": """
&chain n = 4, amplitude = 1.5, omega = 1.5 /
&initial kind = 'random', seed = 2, x_amp = 0.2, v_amp = 0.2 /
&run transient = 5, cycles = 6 /
&output file = 'run.h5' /
&sweep parameter = 'amplitude', start = 1.5, stop = 1.7, step = 0.1, mode = 'independent',
       parameter2 = 'damping', start2 = 0.05, stop2 = 0.1, step2 = 0.05 /
""",
}


@pytest.mark.parametrize("text", RESOLVED_CASES.values(), ids=RESOLVED_CASES.keys())
def test_resolved_namelist_reads_back(impactchain_exe, tmp_path, text):
    """/@resolved_namelist names every key as used (lists in full, reals to full precision):
    run on it, the simulator gives the same datasets and the same resolved text."""
    run_namelist(impactchain_exe, text, tmp_path)
    with h5py.File(tmp_path / "run.h5") as f:
        resolved = f.attrs["resolved_namelist"]
        resolved = resolved.decode() if isinstance(resolved, bytes) else str(resolved)
    for group in ("&chain", "&initial", "&run", "&lyapunov", "&output"):
        assert group in resolved
    for key in ("spacing =", "stick_speed =", "max_period =", "align ="):
        assert key in resolved
    if "x0" in text:
        assert "x0 = " in resolved and "v0 = " in resolved
    if "&sweep" in text:
        assert "&sweep parameter = 'amplitude'" in resolved and "parameter2 = 'damping'" in resolved
    again = resolved.replace("'run.h5'", "'again.h5'")
    run_namelist(impactchain_exe, again, tmp_path, name="again.nml")
    with h5py.File(tmp_path / "run.h5") as a, h5py.File(tmp_path / "again.h5") as b:
        second = b.attrs["resolved_namelist"]
        second = second.decode() if isinstance(second, bytes) else str(second)
        assert second == again
        names = []
        a.visititems(lambda name, obj: names.append(name) if isinstance(obj, h5py.Dataset)
                     else None)
        assert len(names) > 5
        for name in names:
            np.testing.assert_array_equal(a[name][()], b[name][()], err_msg=name)


def _installed(name: str) -> Path:
    program = ROOT / ".venv" / "bin" / name
    if not program.exists():
        pytest.skip(f"{name} is not installed in .venv (make build installs it)")
    return program


def test_the_programs_on_the_path_run_from_any_directory(impactchain_exe, tmp_path):
    """Issue 32, 4: after `make` the simulator and the MPI driver are programs of the venv
    (`.venv/bin`, on the PATH once it is active; `pip install .` installs them likewise): run
    from another directory, each writes its file next to its input, and the simulator's
    records are those of the fpm build, bit for bit (the same flags: meson.build)."""
    if os.environ.get("IMPACTCHAIN_FPM_FLAGS"):
        pytest.skip("compared with the release build, in the release pass of the tests")
    simulator = _installed("impactchain")
    inputs, elsewhere = tmp_path / "inputs", tmp_path / "elsewhere"
    inputs.mkdir()
    elsewhere.mkdir()
    text = ("&chain n = 8, amplitude = 1.7, omega = 1.5 /\n"
            "&initial kind = 'random', seed = 1, x_amp = 0.3, v_amp = 0.3 /\n"
            "&run transient = 10, cycles = 50 /\n")
    (inputs / "run.nml").write_text(text)
    ran = subprocess.run([str(simulator), "--quiet", "../inputs/run.nml"], cwd=elsewhere,
                         capture_output=True, text=True, timeout=120)
    assert ran.returncode == 0, ran.stderr
    assert "wrote ../inputs/run.h5" in ran.stdout
    assert not list(elsewhere.iterdir())
    subprocess.run([str(impactchain_exe), "--quiet", "run.nml", "-o", "fpm.h5"], cwd=inputs,
                   check=True, capture_output=True, timeout=120)
    with h5py.File(inputs / "run.h5") as a, h5py.File(inputs / "fpm.h5") as b:
        for name in ("strobe/x", "strobe/v", "events/time", "final/x"):
            assert np.array_equal(a[name][()], b[name][()]), name

    if shutil.which("mpirun") is None:
        return
    driver = _installed("impactchain-mpi")
    (inputs / "sweep.nml").write_text(text + "&sweep parameter = 'amplitude', start = 1.5, "
                                      "stop = 1.7, step = 0.05, mode = 'independent' /\n")
    ran = subprocess.run(["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", "2",
                          str(driver), "--quiet", "../inputs/sweep.nml"], cwd=elsewhere,
                         capture_output=True, text=True, timeout=300)
    assert ran.returncode == 0, ran.stderr
    assert "wrote ../inputs/sweep.h5" in ran.stdout and "on 2 ranks" in ran.stdout
    assert not list(elsewhere.iterdir())


def _readme_block_after(marker: str) -> str:
    """The first ```sh block of the sweeps guide (docs/sweeps.md) after the line holding
    `marker`."""
    text = (ROOT / "docs" / "sweeps.md").read_text()
    rest = text[text.index(marker):]
    start = rest.index("```sh\n") + len("```sh\n")
    return rest[start:rest.index("```", start)]


def test_the_readmes_mpi_commands_run_as_written(tmp_path):
    """Issue 32, 4: the README's MPI command and its Slurm job script run as written (with 2
    ranks; the job's `srun` as `mpirun -np 2`, its /path/to/impactchain this repository), from
    the namelist's directory, each writing its sweep next to it."""
    if os.environ.get("IMPACTCHAIN_FPM_FLAGS"):
        pytest.skip("the installed programs are the release build: run in that pass")
    _installed("impactchain-mpi")
    if shutil.which("mpirun") is None:
        pytest.skip("no mpirun")
    sweep = ("&chain n = 8, amplitude = 1.7, omega = 1.5 /\n"
             "&initial kind = 'random', seed = 1, x_amp = 0.3, v_amp = 0.3 /\n"
             "&run transient = 10, cycles = 40 /\n&sweep parameter = 'amplitude', "
             "start = 1.5, stop = 1.7, step = 0.05, mode = 'independent' /\n")
    (tmp_path / "input.nml").write_text(sweep)
    (tmp_path / "sweep.nml").write_text(sweep)
    command = _readme_block_after("MPI driver `impactchain-mpi` is built")
    assert "mpirun -np 4 impactchain-mpi input.nml" in command
    job = _readme_block_after("Under Slurm, one task per rank")
    assert "srun impactchain-mpi sweep.nml" in job
    scripts = {"command": command.replace("-np 4", "-np 2").replace("/path/to/impactchain",
                                                                     str(ROOT)),
               "job": job.replace("/path/to/impactchain", str(ROOT)).replace(
                   "srun ", "mpirun -np 2 ")}
    # (mpirun as root, on a machine of fewer cores than ranks: allowed through its environment)
    env = {**os.environ, "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1",
           "OMPI_MCA_rmaps_base_oversubscribe": "1"}
    for name, script in scripts.items():
        (tmp_path / f"{name}.sh").write_text(script)
        ran = subprocess.run(["bash", "-e", f"{name}.sh"], cwd=tmp_path, env=env,
                             capture_output=True, text=True, timeout=300)
        assert ran.returncode == 0, (name, ran.stderr)
        assert "on 2 ranks" in ran.stdout, (name, ran.stdout)
    assert (tmp_path / "input.h5").exists() and (tmp_path / "sweep.h5").exists()
