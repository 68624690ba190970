"""The simulator's files are netCDF-4 (schema version 2): every group of a run, a Lyapunov run
with the Jacobian, a stopped run (its /resume), a 1-D and a 2-D sweep and a census opens in
xarray through h5netcdf with named dimensions and coordinates and no warning (pytest turns
warnings into errors); every variable has long_name and UDUNITS units; coded integers carry
flags."""
from __future__ import annotations

import signal
from pathlib import Path

import h5py
import numpy as np
import pytest

from simulator import impactchain_exe, run_namelist, start_until_progress  # noqa: F401

xr = pytest.importorskip("xarray")
pytest.importorskip("h5netcdf")

CHAIN = "&chain n = 5, amplitude = 1.7, omega = 1.5 /\n"
START = "&initial kind = 'random', seed = 3, x_amp = 0.3, v_amp = 0.3 /\n"
RUN = CHAIN + START + "&run transient = 10, cycles = 30 /\n&output file = '{out}' /\n"
LYAPUNOV = (CHAIN + START + "&run transient = 10, cycles = 40 /\n"
            "&lyapunov vectors = 6, qr_every = 2, jacobian = .true. /\n"
            "&output file = '{out}' /\n")
SWEEP_1D = (CHAIN + "&initial kind = 'rest' /\n&run transient = 5, cycles = 6, "
            "record_events = .false. /\n&lyapunov vectors = 3 /\n"
            "&sweep parameter = 'omega', start = 1.4, stop = 1.6, step = 0.1 /\n"
            "&output file = '{out}' /\n")
SWEEP_2D = SWEEP_1D.replace(
    "/\n&output", ",\n       parameter2 = 'damping', start2 = 0.05, stop2 = 0.15, step2 = 0.05 /"
    "\n&output")
LONG = (CHAIN + START + "&run cycles = 50000000 /\n&lyapunov vectors = 4 /\n"
        "&output file = '{out}', max_size_mb = 1e6 /\n")
# UDUNITS spellings used: pure numbers (the model's reduced units), bits and radians
UNITS = {"1", "bit", "radian"}


def _groups(path: Path) -> dict[str, object]:
    """Every group of the file, opened with xarray: {name: Dataset}."""
    with h5py.File(path) as f:
        names = [name for name in f if isinstance(f[name], h5py.Group)]
    out = {}
    for name in names:
        with xr.open_dataset(path, engine="h5netcdf", group=name) as ds:
            out[name] = ds.load()
    return out


def _check_described(groups: dict[str, object]) -> None:
    for name, ds in groups.items():
        assert not [d for d in ds.sizes if str(d).startswith("phony_dim")], name
        for var in ds.variables.values():
            assert var.attrs.get("long_name"), (name, var.name)
            assert var.attrs.get("units") in UNITS, (name, var.name, var.attrs.get("units"))
            if "flag_values" in var.attrs:
                assert len(var.attrs["flag_meanings"].split()) == len(var.attrs["flag_values"])
                assert var.attrs["flag_values"].dtype == var.dtype


def test_a_run_is_netcdf(impactchain_exe, tmp_path):
    run_namelist(impactchain_exe, RUN.format(out="run.h5"), tmp_path)
    groups = _groups(tmp_path / "run.h5")
    assert sorted(groups) == ["events", "final", "initial", "params", "stats", "strobe"]
    _check_described(groups)
    strobe = groups["strobe"]
    assert strobe["x"].dims == ("cycle", "oscillator") and strobe["x"].shape == (30, 5)
    np.testing.assert_array_equal(strobe["cycle"], np.arange(11, 41))
    np.testing.assert_array_equal(strobe["oscillator"], np.arange(1, 6))
    assert strobe["period"].dims == ("oscillator",)
    assert strobe["x"].attrs["model_units"] == "length"
    events = groups["events"]
    assert events["time"].dims == ("event",) and events.sizes["event"] > 0
    assert list(events["kind"].attrs["flag_values"]) == [0, 1, 2, 3]
    final = groups["final"]
    assert final["event_time"].dims == ("bond",) and final["x"].dims == ("oscillator",)
    assert final["phase"].dims == () and final["cycle"].dims == ()
    np.testing.assert_array_equal(final["bond"], np.arange(0, 6))
    assert groups["stats"]["site_counts"].dims == ("bond",)
    assert groups["params"]["spacing"].dims == ("bond",)
    params = groups["params"].attrs
    assert params["boundary"] == "fixed" and params["n"] == 5 and np.ndim(params["omega"]) == 0
    with h5py.File(tmp_path / "run.h5") as f:
        assert f.attrs["schema_version"] == 2 and np.ndim(f.attrs["schema_version"]) == 0
        assert isinstance(f.attrs["input_namelist"], str)
        string = f.attrs.get_id("input_namelist").get_type()
        assert string.is_variable_str() and string.get_cset() == h5py.h5t.CSET_UTF8
        for name in ("strobe/x", "strobe/v", "strobe/cycle", "events/time", "events/kind"):
            if h5py.h5z.filter_avail(h5py.h5z.FILTER_DEFLATE):
                assert f[name].compression == "gzip" and f[name].shuffle, name
    with xr.open_dataset(tmp_path / "run.h5", engine="h5netcdf") as root:
        assert root.attrs["schema_version"] == 2 and root.attrs["complete"] == 1


def test_a_lyapunov_run_is_netcdf(impactchain_exe, tmp_path):
    run_namelist(impactchain_exe, LYAPUNOV.format(out="l.h5"), tmp_path)
    groups = _groups(tmp_path / "l.h5")
    assert {"lyapunov", "floquet"} <= set(groups)
    _check_described(groups)
    lyap = groups["lyapunov"]
    assert lyap["exponents"].dims == ("exponent",) and lyap.sizes["exponent"] == 6
    assert lyap["running"].dims == ("qr_step", "exponent")
    # running_cycle is a coordinate of running (netCDF's `coordinates` attribute)
    assert "running_cycle" in lyap.coords and lyap["running_cycle"].dims == ("qr_step",)
    assert lyap["exponents"].attrs["units"] == "bit"
    floquet = groups["floquet"]
    assert floquet["jacobian"].dims == ("row", "column") and floquet["jacobian"].shape == (10, 10)
    assert floquet["multipliers_re"].dims == ("multiplier",)


def test_a_stopped_run_and_its_resume_are_netcdf(impactchain_exe, tmp_path):
    (tmp_path / "long.nml").write_text(LONG.format(out="long.h5"))
    proc, _ = start_until_progress(impactchain_exe, ["long.nml"], tmp_path)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 3, err
    groups = _groups(tmp_path / "long.h5")
    assert "resume" in groups
    _check_described(groups)
    resume = groups["resume"]
    assert resume["tangent"].dims == ("state", "vector") and resume["tangent"].shape == (10, 4)
    assert resume["start_cycle"].dims == () and resume["same_instant"].dims == ()
    assert groups["strobe"].sizes["cycle"] == groups["stats"]["cycles_done"]


def test_a_1d_sweep_is_netcdf(impactchain_exe, tmp_path):
    run_namelist(impactchain_exe, SWEEP_1D.format(out="s.h5"), tmp_path)
    groups = _groups(tmp_path / "s.h5")
    _check_described(groups)
    sweep = groups["sweep"]
    np.testing.assert_allclose(sweep["point"], [1.4, 1.5, 1.6], atol=1e-12)
    assert sweep["point"].attrs["long_name"].startswith("omega")
    assert sweep["x"].dims == ("point", "record", "oscillator") and sweep["x"].shape == (3, 6, 5)
    assert sweep["exponents"].dims == ("point", "exponent")
    assert sweep["period"].dims == ("point", "oscillator")
    # the drive period per point; /params holds neither omega nor its period
    np.testing.assert_allclose(sweep["drive_period"], 2 * np.pi / sweep["point"], rtol=1e-15)
    assert sweep["drive_period"].dims == ("point",)
    assert not {"omega", "drive_period"} & set(groups["params"].attrs)
    assert groups["params"].attrs["amplitude"] == 1.7
    assert sweep.sel(point=1.5, method="nearest")["x"].shape == (6, 5)


@pytest.mark.parametrize("sweep", [False, True])
def test_a_census_is_netcdf(impactchain_exe, tmp_path, sweep):
    text = (CHAIN + "&run transient = 20, cycles = 20 /\n&census samples = 4 /\n"
            "&output file = 'c.h5' /\n")
    if sweep:
        text += "&sweep parameter = 'omega', start = 1.4, stop = 1.5, step = 0.1 /\n"
    run_namelist(impactchain_exe, text, tmp_path)
    groups = _groups(tmp_path / "c.h5")
    _check_described(groups)
    census = groups["census"]
    assert census["x0"].dims == ("point", "sample", "oscillator")
    assert census["x0"].shape == (2 if sweep else 1, 4, 5)
    assert census["attractor_x"].dims == ("attractor", "oscillator")
    assert census["sample_exponents"].dims == ("point", "sample", "exponent")
    assert census["attractor_exponents"].dims == ("attractor", "exponent")
    assert ("omega" in groups["params"].attrs) is not sweep


def test_a_2d_sweep_is_netcdf(impactchain_exe, tmp_path):
    run_namelist(impactchain_exe, SWEEP_2D.format(out="s2.h5"), tmp_path)
    groups = _groups(tmp_path / "s2.h5")
    _check_described(groups)
    sweep = groups["sweep"]
    np.testing.assert_allclose(sweep["point2"], [0.05, 0.10, 0.15], atol=1e-12)
    assert sweep["x"].dims == ("point", "point2", "record", "oscillator")
    assert sweep["x"].shape == (3, 3, 6, 5)
    assert sweep["ky_dimension"].dims == ("point", "point2")
    assert sweep["drive_period"].dims == ("point",)
    assert not {"omega", "drive_period", "damping"} & set(groups["params"].attrs)


def test_a_run_starts_from_the_final_state_of_either_version(impactchain_exe, tmp_path):
    """&initial kind = 'file' reads /final and /params of schema version 1 (fixed-length
    strings, one-element arrays) and of version 2 alike: the same state, the same run."""
    data = Path(__file__).resolve().parent / "package" / "data"
    records = {}
    for version in (1, 2):
        text = ("&chain n = 3, amplitude = 1.7, omega = 1.5 /\n"
                f"&initial kind = 'file', file = '{data / f'v{version}_run.h5'}' /\n"
                f"&run transient = 0, cycles = 8 /\n&output file = 'from{version}.h5' /\n")
        run_namelist(impactchain_exe, text, tmp_path, f"from{version}.nml")
        with h5py.File(tmp_path / f"from{version}.h5") as f:
            records[version] = f["strobe/x"][()]
    assert records[1].shape == (8, 3)
    np.testing.assert_array_equal(records[1], records[2])
