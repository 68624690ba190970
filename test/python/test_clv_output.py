"""/clv of a run with covariant Lyapunov vectors (docs/model.md section 14): its layout read by
h5py and xarray (named dimensions, coordinates the records' drive cycles), numbers that must
hold whatever the chain (unit vectors, weights summing to 1, participation ratios in [1/n, 1],
the vectors' growth rates against /lyapunov), the input checked key by key, and a run stopped
early, which is run again rather than continued."""
from __future__ import annotations

import re
import signal
import subprocess

import h5py
import numpy as np
import pytest

from simulator import impactchain_exe, run_namelist, start_until_progress  # noqa: F401

RUN = """&chain n = 4, amplitude = 4.15, omega = 1.5, restitution = 0.85 /
&initial kind = 'random', seed = 3, x_amp = 0.2, v_amp = 0.2 /
&run transient = 100, cycles = 700, record_events = .false. /
&lyapunov covariant = .true., clv_transient = 200, clv_store = 3, clv_save = 2 {extra}/
&output file = 'clv.h5' /
"""


def test_clv_group_layout_and_invariants(impactchain_exe, tmp_path):
    run_namelist(impactchain_exe, RUN.format(extra=""), tmp_path)
    with h5py.File(tmp_path / "clv.h5") as f:
        g = f["clv"]
        kept = 700 - 200
        assert g["ipr"].shape == (kept, 8)
        assert g["site_weight"].shape == (kept, 3, 4)
        assert g["min_angle"].shape == (kept,)
        assert g["vectors"].shape == (2, 8, 8)
        assert g.attrs["clv_transient"] == 200 and g.attrs["unstable"] == 1
        np.testing.assert_array_equal(g["cycle"][:], f["strobe/cycle"][:kept])
        np.testing.assert_array_equal(g["saved_cycle"][:], f["strobe/cycle"][kept - 2:kept])
        np.testing.assert_allclose(np.linalg.norm(g["vectors"][:], axis=2), 1, atol=1e-14)
        np.testing.assert_allclose(g["site_weight"][:].sum(axis=2), 1, atol=1e-14)
        ipr = g["ipr"][:]
        assert np.all((ipr >= 0.25 - 1e-14) & (ipr <= 1))
        angle = g["min_angle"][:]
        assert np.all((angle > 0) & (angle <= np.pi / 2))
        # the weights of the first vectors are those of their own participation ratios
        np.testing.assert_allclose((g["site_weight"][:] ** 2).sum(axis=2), ipr[:, :3],
                                   rtol=1e-12)
        gap = np.abs(g["exponents"][:] - f["lyapunov/exponents"][:])
        assert np.all(gap <= 3 * np.hypot(g["stderr"][:], f["lyapunov/stderr"][:]))
        assert np.all(g["stderr_block"][:] >= 1) and np.all(g["stderr"][:] > 0)
        assert g["exponents"].attrs["units"] == "bit"
        assert g["min_angle"].attrs["units"] == "radian"


def test_clv_group_is_a_netcdf_group(impactchain_exe, tmp_path):
    xr = pytest.importorskip("xarray")
    run_namelist(impactchain_exe, RUN.format(extra=""), tmp_path)
    with xr.open_dataset(tmp_path / "clv.h5", group="clv") as ds:
        assert ds["ipr"].dims == ("cycle", "vector")
        assert ds["site_weight"].dims == ("cycle", "leading_vector", "oscillator")
        assert ds["vectors"].dims == ("saved_cycle", "vector", "component")
        assert ds["exponents"].dims == ("vector",)
        assert list(ds["vector"].values) == list(range(1, 9))
        assert ds["cycle"].values[0] == 101


def test_clv_read_by_impactchain_io(impactchain_exe, tmp_path):
    """impactchain.io's Run.clv holds the file's /clv, records first, in the simulator's units."""
    from impactchain.io import read_run

    run_namelist(impactchain_exe, RUN.format(extra=""), tmp_path)
    run = read_run(tmp_path / "clv.h5", require=("clv", "clv/site_weight"))
    clv = run.clv
    assert clv is not None and run.strobe is not None
    assert (clv.n_record, clv.k, clv.stored, clv.unstable, clv.clv_transient) == (500, 8, 3, 1,
                                                                                 200)
    np.testing.assert_array_equal(clv.cycle, run.strobe.cycle[:500])
    np.testing.assert_array_equal(clv.saved_cycle, run.strobe.cycle[498:500])
    with h5py.File(tmp_path / "clv.h5") as f:
        g = f["clv"]
        for name in ("exponents", "stderr", "stderr_block", "ipr", "min_angle", "site_weight",
                     "vectors"):
            np.testing.assert_array_equal(getattr(clv, name), g[name][:], err_msg=name)
    assert run.unit("clv/exponents") == run.unit("lyapunov/exponents") == "bits per drive cycle"
    assert run.unit("clv/min_angle") == "radian" and run.unit("clv/cycle") == "drive cycles"
    assert run.clv.site_weight.shape == (500, 3, 4)
    # clv_store = 0 and clv_save = 0: no /clv/site_weight, /clv/vectors, /clv/saved_cycle
    text = RUN.format(extra="").replace("clv_store = 3, clv_save = 2", "clv_store = 0, "
                                        "clv_save = 0").replace("clv.h5", "bare.h5")
    run_namelist(impactchain_exe, text, tmp_path, name="bare.nml")
    bare = read_run(tmp_path / "bare.h5").clv
    assert bare is not None and bare.stored == 0 and bare.vectors is None
    np.testing.assert_array_equal(bare.ipr, clv.ipr)


@pytest.mark.parametrize("extra, needle", [
    ("clv_transient = 700", "clv_transient = 700 is outside [1, cycles - 1 = 699]"),
    ("clv_store = 9", "clv_store = 9 is outside [0, vectors = 8]"),
    ("clv_save = 501", "clv_save = 501 is outside [0, cycles - clv_transient = 500]"),
    ("qr_every = 3", "qr_every = 3 must be 0 or 1"),
    ("enabled = .false.", "covariant = .true. needs enabled = .true."),
])
def test_bad_keys_are_named(impactchain_exe, tmp_path, extra, needle):
    # a key of RUN's &lyapunov gets the new value in place (a key given twice is refused)
    key = extra.split(" =")[0]
    text = RUN.format(extra="")
    if f"{key} = " in text:
        text = re.sub(rf"{key} = [^,/ ]+", extra, text)
    else:
        text = RUN.format(extra=", " + extra)
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode == 1
    assert needle in result.stderr, result.stderr
    assert not list(tmp_path.glob("*.h5*"))


@pytest.mark.parametrize("cycles, vectors, transient, stored", [
    (10, 2, 5, 2),      # a short run: half its records converge the backward pass
    (1000, 0, 200, 4),  # the usual defaults
])
def test_defaults_fit_the_run(impactchain_exe, tmp_path, cycles, vectors, transient, stored):
    """Without clv_transient and clv_store, a covariant run of any length and any number of
    vectors is valid: min(200, cycles / 2) records converge, min(4, k) weights are kept."""
    text = (f"&chain n = 4, amplitude = 4.15, omega = 1.5 /\n&run cycles = {cycles} /\n"
            f"&lyapunov covariant = .true., vectors = {vectors} /\n&output file = 'd.h5' /\n")
    run_namelist(impactchain_exe, text, tmp_path)
    with h5py.File(tmp_path / "d.h5") as f:
        assert f["clv"].attrs["clv_transient"] == transient
        assert f["clv/site_weight"].shape[1] == stored
        assert f["clv/ipr"].shape[0] == cycles - transient


def test_one_cycle_is_too_short(impactchain_exe, tmp_path):
    text = ("&chain n = 4, amplitude = 4.15, omega = 1.5 /\n&run cycles = 1 /\n"
            "&lyapunov covariant = .true. /\n&output file = 'd.h5' /\n")
    result = run_namelist(impactchain_exe, text, tmp_path, check=False)
    assert result.returncode == 1
    assert "covariant = .true. needs &run cycles >= 2" in result.stderr, result.stderr
    assert not list(tmp_path.glob("*.h5*"))


def test_stopped_run_is_run_again_not_continued(impactchain_exe, tmp_path):
    text = RUN.format(extra="").replace("cycles = 700", "cycles = 2000000")
    (tmp_path / "input.nml").write_text(text)
    run, _ = start_until_progress(impactchain_exe, ["input.nml"], tmp_path)
    run.send_signal(signal.SIGINT)
    _, stderr = run.communicate(timeout=60)
    assert run.returncode == 3, stderr
    assert "without covariant vectors" in stderr
    with h5py.File(tmp_path / "clv.h5") as f:
        assert f.attrs["complete"] == 0 and "clv" not in f
    again = subprocess.run([str(impactchain_exe), "--quiet", "input.nml"], cwd=tmp_path,
                           capture_output=True, text=True, timeout=60)
    assert again.returncode == 1
    assert "cannot be continued" in again.stderr and "overwrite" in again.stderr
