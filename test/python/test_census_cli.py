"""The command line's attractor censuses (`&census`): bad input named with its key and the
allowed range, exit 1 and no file; the /census group read by xarray (figure 3's chain: its two
mirror-image period-8 patterns merged or kept apart, fractions summing to one); a census along
a sweep; the same file with 1 and 2 threads, and after an interrupted census is resumed."""
from __future__ import annotations

import os
import signal
import subprocess
import time
from pathlib import Path

import h5py
import numpy as np
import pytest
import xarray as xr

from simulator import impactchain_exe, run_namelist  # noqa: F401 (fixture)

FIG3 = ("&chain n = 15, amplitude = 2.2, omega = 1.5, damping = 0.05, restitution = 0.7 /\n"
        "&run transient = 2000, cycles = 48, max_period = 8 /\n")

BAD = {
    "no samples": ("samples = 0", ["&census: samples = 0 is outside [1, 10000000]"]),
    "overlapping starts": ("x_amp = 0.6", ["&census: x_amp = 0.6",
                                           "half the smallest spacing = 0.5"]),
    "negative speed amplitude": ("v_amp = -1", ["&census: v_amp = -1", "[0, 1e6]"]),
    "tolerance": ("tolerance = 0", ["&census: tolerance = 0", "(0, 1)"]),
    "mirror": ("mirror = 'flip'", ["mirror = 'flip' is not one of 'merge', 'separate'"]),
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
    assert (ds.attractor_period.values[~periodic] == 0).all()
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


def assert_same_census(a: Path, b: Path) -> None:
    with h5py.File(a) as fa, h5py.File(b) as fb:
        assert sorted(fa["census"]) == sorted(fb["census"])
        for key in fa["census"]:
            np.testing.assert_array_equal(fa["census"][key][()], fb["census"][key][()],
                                          err_msg=key)
        for key in fa["census"].attrs:
            assert fa["census"].attrs[key] == fb["census"].attrs[key], key


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
    proc = subprocess.Popen([str(impactchain_exe), "--quiet", "part.nml"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(1.0)
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
