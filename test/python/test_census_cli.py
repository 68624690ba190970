"""The command line's attractor censuses (`&census`): bad input named with its key and the
allowed range, exit 1 and no file; the /census group read by xarray (figure 3's chain: its two
mirror-image period-8 patterns merged or kept apart, fractions summing to one); a census along
a sweep; an ensemble of spectra (`exponents = k`) and its datasets; the same file with 1 and 2
threads, and after an interrupted census is resumed; the same file from the MPI driver on 2
ranks (also with k exponents per sample), also after a stop by SIGTERM resumed on 3 ranks or by
the threaded driver."""
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
import xarray as xr

from simulator import (child_pids, impactchain_exe, mpi_exe,  # noqa: F401 (fixtures)
                       run_namelist, start_until_progress)

FIG3 = ("&chain n = 15, amplitude = 2.2, omega = 1.5, damping = 0.05, restitution = 0.7 /\n"
        "&run transient = 2000, cycles = 48, max_period = 8 /\n")

BAD = {
    "no samples": ("samples = 0", ["&census: samples = 0 is outside [1, 10000000]"]),
    "overlapping starts": ("x_amp = 0.6", ["&census: x_amp = 0.6",
                                           "half the smallest spacing = 0.5"]),
    "negative speed amplitude": ("v_amp = -1", ["&census: v_amp = -1", "[0, 1e6]"]),
    "tolerance": ("tolerance = 0", ["&census: tolerance = 0", "(0, 1)"]),
    "mirror": ("mirror = 'flip'", ["mirror = 'flip' is not one of 'merge', 'separate'"]),
    "no exponents": ("exponents = 0", ["&census: exponents = 0 is outside [1, 2n = 30]"]),
    "more exponents than 2n": ("exponents = 31",
                               ["&census: exponents = 31 is outside [1, 2n = 30]"]),
    "misspelt key": ("sample = 5", ["unknown key 'sample'", "did you mean 'samples'"]),
}


@pytest.mark.parametrize("case", sorted(BAD))
def test_bad_census_input_is_refused(impactchain_exe, tmp_path, case):
    keys, needles = BAD[case]
    text = FIG3 + f"&census {keys} /\n&output file = 'bad.h5' /\n"
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode == 1
    for needle in needles:
        assert needle in result.stderr, result.stderr
    assert not list(tmp_path.glob("*.h5*"))


@pytest.mark.parametrize("mirror", ["merge", "separate"])
def test_census_file(impactchain_exe, tmp_path, mirror):
    """Eight starts of figure 3's chain: every sample on a periodic attractor of period 8
    (or a chaotic one), the mirror images merged into one attractor with the flag set, or
    kept as two; the layout read by xarray."""
    text = (FIG3 + f"&census samples = 8, seed = 2, x_amp = 0.3, v_amp = 1.0, "
            f"mirror = '{mirror}' /\n&output file = 'census.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path)
    assert "attractor 0 (point 0)" in result.stdout
    ds = xr.open_dataset(tmp_path / "census.h5", engine="h5netcdf", group="census")
    assert ds.x0.dims == ("point", "sample", "oscillator") and ds.x0.shape == (1, 8, 15)
    assert ds.sample_attractor.dims == ("point", "sample")
    assert ds.fraction.dims == ("point", "attractor")
    assert ds.attractor_sites.dims == ("attractor", "bond")
    assert list(ds.sample.values) == list(range(1, 9))
    assert ds.attrs["mirror"] == mirror and ds.attrs["samples"] == 8
    assert "lambda1 > 3 standard errors" in ds.attrs["rule"]
    assert np.isclose(ds.fraction.sum("attractor").values, 1.0, rtol=0, atol=1e-12).all()
    ids = ds.sample_attractor.values[0]
    counts = np.bincount(ids, minlength=ds.sizes["attractor"])
    np.testing.assert_array_equal(ds.fraction.values[0], counts / 8)
    np.testing.assert_allclose(ds.fraction_stderr.values[0],
                               np.sqrt(counts / 8 * (1 - counts / 8) / 8), rtol=1e-15)
    kinds = ds.attractor_kind.values.astype(str)
    periodic = kinds == "periodic"
    assert periodic.any()
    assert (ds.attractor_period.values[periodic] == 8).any()
    # an attractor that is not periodic has an oscillator without a period (others may have
    # one: the census's 'aperiodic, not chaotic' kind)
    assert (ds.attractor_period.values[~periodic] == 0).any(axis=-1).all()
    assert (np.abs(ds.x0.values) <= 0.3).all() and (np.abs(ds.v0.values) <= 1.0).all()
    # the representative is the first sample that reached the attractor
    first = [int(np.argmax(ids == a)) + 1 for a in range(ds.sizes["attractor"])]
    np.testing.assert_array_equal(ds.attractor_sample.values, first)
    if mirror == "merge":
        assert (ds.mirrored.values[0][periodic[ids]] == 1).any()
    else:
        assert (ds.mirrored.values == 0).all()
    with h5py.File(tmp_path / "census.h5") as f:
        assert f.attrs["complete"] == 1


def test_census_along_a_sweep(impactchain_exe, tmp_path):
    text = (FIG3 + "&census samples = 3, x_amp = 0.3, v_amp = 1.0 /\n"
            "&sweep parameter = 'amplitude', start = 2.2, stop = 2.3, step = 0.1 /\n"
            "&output file = 'sweep.h5' /\n")
    run_namelist(impactchain_exe, text, tmp_path)
    ds = xr.open_dataset(tmp_path / "sweep.h5", engine="h5netcdf", group="census")
    np.testing.assert_allclose(ds.point.values, [2.2, 2.3], rtol=1e-15)
    assert ds.attrs["parameter"] == "amplitude"
    np.testing.assert_array_equal(ds.x0.values[0], ds.x0.values[1])
    at_point = ds.attractor_point.values
    ids = ds.sample_attractor.values
    assert (at_point[ids[0]] == 0).all() and (at_point[ids[1]] == 1).all()
    assert np.isclose(ds.fraction.sum("attractor").values, 1.0, atol=1e-12).all()
    with h5py.File(tmp_path / "sweep.h5") as f:
        assert "amplitude" not in f["params"].attrs


SMALL = ("&chain n = 4, amplitude = 1.0, omega = 0.9, damping = 0.05, restitution = 0.7 /\n"
         "&run transient = 300, cycles = 200, max_period = 8 /\n")


def test_an_ensemble_of_spectra(impactchain_exe, tmp_path):
    """exponents = 2n on a chain of four: per sample its 8 exponents, descending, the first
    lambda1 bit for bit, with their standard errors; per attractor the mean over its samples
    and the standard deviation between them (n - 1), both on the `exponent` dimension; the
    key in the file's resolved namelist. The default census has one exponent per sample and
    the same datasets as before besides."""
    text = (SMALL + "&census samples = 12, seed = 3, x_amp = 0.3, v_amp = 1.0, exponents = 8 /\n"
            "&output file = 'spectra.h5' /\n")
    run_namelist(impactchain_exe, text, tmp_path)
    ds = xr.open_dataset(tmp_path / "spectra.h5", engine="h5netcdf", group="census")
    assert ds.sample_exponents.dims == ("point", "sample", "exponent")
    assert ds.sample_exponents.shape == (1, 12, 8)
    assert ds.sample_exponents_stderr.dims == ("point", "sample", "exponent")
    assert ds.attractor_exponents.dims == ds.attractor_exponents_spread.dims == \
        ("attractor", "exponent")
    assert list(ds.exponent.values) == list(range(1, 9))
    assert ds.sample_exponents.attrs["model_units"] == "bits per drive cycle"
    spectra = ds.sample_exponents.values
    np.testing.assert_array_equal(spectra[..., 0], ds.lambda1.values)
    assert (np.diff(spectra, axis=2) <= 0).all()
    assert (ds.sample_exponents_stderr.values >= 0).all()
    ids = ds.sample_attractor.values[0]
    for a in range(ds.sizes["attractor"]):
        members = spectra[0][ids == a]
        np.testing.assert_allclose(ds.attractor_exponents.values[a], members.mean(axis=0),
                                   rtol=1e-13, atol=1e-14)
        spread = members.std(axis=0, ddof=1) if len(members) > 1 else np.zeros(8)
        np.testing.assert_allclose(ds.attractor_exponents_spread.values[a], spread,
                                   rtol=1e-12, atol=1e-14)
    with h5py.File(tmp_path / "spectra.h5") as f:
        assert "exponents = 8" in f.attrs["resolved_namelist"]
    # the default: one exponent, and the key left out of the resolved namelist
    run_namelist(impactchain_exe, text.replace(", exponents = 8", "").replace(
        "spectra.h5", "one.h5"), tmp_path, "one.nml")
    with h5py.File(tmp_path / "one.h5") as f:
        assert f["census/sample_exponents"].shape == (1, 12, 1)
        np.testing.assert_array_equal(f["census/sample_exponents"][..., 0],
                                      f["census/lambda1"][()])
        assert "exponents" not in f.attrs["resolved_namelist"]


def assert_same_census(a: Path, b: Path) -> None:
    with h5py.File(a) as fa, h5py.File(b) as fb:
        assert sorted(fa["census"]) == sorted(fb["census"])
        for key in fa["census"]:
            np.testing.assert_array_equal(fa["census"][key][()], fb["census"][key][()],
                                          err_msg=key)
        assert sorted(fa["census"].attrs) == sorted(fb["census"].attrs)
        for key in fa["census"].attrs:
            np.testing.assert_array_equal(fa["census"].attrs[key], fb["census"].attrs[key],
                                          err_msg=key)


LONG = ("&chain n = 15, amplitude = 2.2, omega = 1.5, damping = 0.05, restitution = 0.7 /\n"
        "&run transient = 300, cycles = 32, max_period = 8 /\n"
        "&census samples = {samples}, x_amp = 0.3, v_amp = 1.0 /\n&output file = '{out}' /\n")


def run_threads(exe, tmp_path, text, threads, name):
    (tmp_path / name).write_text(text)
    env = dict(os.environ, OMP_NUM_THREADS=str(threads))
    result = subprocess.run([str(exe), "--quiet", name], cwd=tmp_path, env=env,
                            capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    return result


def test_threads_give_identical_censuses(impactchain_exe, tmp_path):
    run_threads(impactchain_exe, tmp_path, LONG.format(samples=24, out="one.h5"), 1, "one.nml")
    run_threads(impactchain_exe, tmp_path, LONG.format(samples=24, out="two.h5"), 2, "two.nml")
    assert_same_census(tmp_path / "one.h5", tmp_path / "two.h5")


def test_interrupted_census_resumes_to_the_same_file(impactchain_exe, tmp_path):
    samples = 1000
    run_namelist(impactchain_exe, LONG.format(samples=samples, out="whole.h5"), tmp_path,
                 "whole.nml")
    (tmp_path / "part.nml").write_text(LONG.format(samples=samples, out="part.h5"))
    # stopped once a sample is done (the first progress line), long before the last
    proc, _ = start_until_progress(impactchain_exe, ["part.nml"], tmp_path, "sample")
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, err
    assert "the census was stopped after" in err
    assert (tmp_path / "part.h5.ckpt").exists()
    assert not (tmp_path / "part.h5").exists()
    result = run_namelist(impactchain_exe, LONG.format(samples=samples, out="part.h5"),
                          tmp_path, "part.nml")
    resumed = int(result.stdout.split("resumed from a checkpoint: ")[1].split(")")[0])
    assert 0 < resumed < samples
    assert not (tmp_path / "part.h5.ckpt").exists()
    assert_same_census(tmp_path / "whole.h5", tmp_path / "part.h5")


MPIRUN = ["mpirun", "--allow-run-as-root", "--oversubscribe"]

SWEEP = ("&chain n = 15, amplitude = 2.2, omega = 1.5, damping = 0.05, restitution = 0.7 /\n"
         "&run transient = 300, cycles = 32, max_period = 8 /\n"
         "&census samples = 11, seed = 5, x_amp = 0.3, v_amp = 1.0 /\n"
         "&sweep parameter = 'amplitude', start = 2.2, stop = 2.3, step = 0.1 /\n"
         "&output file = '{out}' /\n")

ENSEMBLE = (SMALL + "&census samples = 11, seed = 5, x_amp = 0.3, v_amp = 1.0, exponents = 8 /\n"
            "&sweep parameter = 'amplitude', start = 1.0, stop = 1.1, step = 0.1 /\n"
            "&output file = '{out}' /\n")

PLANE = ("&chain n = 15, amplitude = 2.2, omega = 1.5, damping = 0.05, restitution = 0.7 /\n"
         "&initial kind = 'explicit', x0 = 15*0.02, v0 = 15*0.1 /\n"
         "&run transient = 300, cycles = 32, max_period = 8 /\n"
         "&census plane = 'x4', 'v12', plane_range = -0.3, 0.3, -1, 1, plane_points = 3 /\n"
         "&output file = '{out}' /\n")


def run_mpi(exe: Path, tmp_path: Path, text: str, name: str, ranks: int = 2,
            env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    (tmp_path / name).write_text(text)
    result = subprocess.run([*MPIRUN, "-np", str(ranks), str(exe), name], cwd=tmp_path,
                            capture_output=True, text=True, timeout=300,
                            env=env or dict(os.environ, OMP_NUM_THREADS="1"))
    assert result.returncode == 0, result.stdout + result.stderr
    return result


@pytest.mark.parametrize("case", ["sweep", "plane", "ensemble"])
def test_ranks_give_the_threaded_census(impactchain_exe, mpi_exe, tmp_path, case):
    """11 samples at each of 2 points (tasks split unevenly over 2 ranks), or a 3 x 3 plane,
    or full spectra (exponents = 2n = 8) of 11 samples at 2 points of a chain of four: the
    MPI driver's /census equals the threaded driver's bit for bit."""
    if mpi_exe is None:
        pytest.skip("mpifort is not installed: the MPI comparison needs openmpi")
    text = {"sweep": SWEEP, "plane": PLANE, "ensemble": ENSEMBLE}[case]
    run_threads(impactchain_exe, tmp_path, text.format(out="one.h5"), 2, "one.nml")
    result = run_mpi(mpi_exe, tmp_path, text.format(out="mpi.h5"), "mpi.nml")
    assert "impactchain-mpi: wrote mpi.h5" in result.stdout
    assert "on 2 ranks" in result.stdout and "attractor 0 (point 0)" in result.stdout
    assert_same_census(tmp_path / "one.h5", tmp_path / "mpi.h5")
    with h5py.File(tmp_path / "mpi.h5") as f:
        assert f.attrs["complete"] == 1
        shapes = {"sweep": (2, 11, 15), "plane": (1, 9, 15), "ensemble": (2, 11, 4)}
        assert f["census/x0"].shape == shapes[case]
        if case == "ensemble":
            assert f["census/sample_exponents"].shape == (2, 11, 8)
    assert not (tmp_path / "mpi.h5.ckpt").exists()


def test_mpi_census_stopped_by_sigterm_resumes(impactchain_exe, mpi_exe, tmp_path):
    """A stop by SIGTERM to every rank leaves the census checkpoint; the same command on 3
    ranks resumes it, and so does the threaded driver (the same checkpoint): both files equal
    an uninterrupted census's."""
    if mpi_exe is None:
        pytest.skip("mpifort is not installed: the MPI test needs openmpi")
    samples = 400
    run_threads(impactchain_exe, tmp_path, LONG.format(samples=samples, out="whole.h5"), 2,
                "whole.nml")
    (tmp_path / "part.nml").write_text(LONG.format(samples=samples, out="part.h5"))
    env = dict(os.environ, OMP_NUM_THREADS="1", IMPACTCHAIN_CHECKPOINT_SECONDS="0.2")
    proc = subprocess.Popen([*MPIRUN, "-np", "2", str(mpi_exe), "part.nml"], cwd=tmp_path,
                            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    ckpt = tmp_path / "part.h5.ckpt"
    deadline = time.monotonic() + 60
    while not ckpt.exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    ranks = child_pids(proc.pid)
    assert ranks, "no MPI ranks found under mpirun"
    for pid in ranks:
        os.kill(pid, signal.SIGTERM)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode != 0, out + err
    assert "the census was stopped after" in err, out + err
    assert ckpt.exists() and not (tmp_path / "part.h5").exists()
    threaded = tmp_path / "threaded"
    threaded.mkdir()
    shutil.copy(ckpt, threaded / "part.h5.ckpt")
    result = run_mpi(mpi_exe, tmp_path, LONG.format(samples=samples, out="part.h5"),
                     "part.nml", ranks=3, env=env)
    resumed = int(result.stdout.split("resumed from a checkpoint: ")[1].split(")")[0])
    assert 0 < resumed < samples
    assert not ckpt.exists()
    assert_same_census(tmp_path / "whole.h5", tmp_path / "part.h5")
    result = run_namelist(impactchain_exe, LONG.format(samples=samples, out="part.h5"),
                          threaded, "part.nml")
    assert f"resumed from a checkpoint: {resumed}" in result.stdout
    assert_same_census(tmp_path / "whole.h5", threaded / "part.h5")
