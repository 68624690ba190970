"""Files of every kind against the file schema (`impactchain --schema`, the one table of
src/runs/chain_file_table.f90): a run with every optional group, a 2-D sweep along omega, a
continuation, one with its fold's curve in two parameters (/curve), censuses at one point and
over a sweep, and a run stopped early (/resume). The recipes' files are checked the same way
in test_recipes.py. See file_schema.py for what is compared. The Python reader names only the
table's paths (impactchain._hdf5).
"""
from __future__ import annotations

import copy
import signal

import h5py
import pytest

from file_schema import read_schema, schema_differences
from impactchain import schema as impactchain_schema
from impactchain._hdf5 import ReaderPathError
from impactchain.io import read_run
from simulator import impactchain_exe, run_namelist, start_until_progress  # noqa: F401

CASES = {
    "run": """&chain n = 4, amplitude = 4.15, omega = 1.5, restitution = 0.85 /
&initial kind = 'random', seed = 3, x_amp = 0.2, v_amp = 0.2 /
&run transient = 20, cycles = 120 /
&lyapunov covariant = .true., clv_transient = 20, clv_store = 2, clv_save = 2, window = 10,
          jacobian = .true. /
&output file = 'out.h5' /
""",
    "sweep_2d": """&chain n = 4, amplitude = 2.0, omega = 1.5 /
&run transient = 10, cycles = 8, record_events = .false. /
&lyapunov vectors = 2 /
&sweep parameter = 'damping', start = 0.05, stop = 0.07, step = 0.01,
       parameter2 = 'omega', start2 = 1.4, stop2 = 1.5, step2 = 0.1 /
&output file = 'out.h5' /
""",
    "continuation": """&chain n = 8, spacing = 1.0, damping = 0.05, restitution = 0.5,
       amplitude = 1.0, omega = 1.9 /
&run transient = 5 /
&continuation parameter = 'amplitude', stop = 1.2, step = 0.05, max_points = 4 /
&output file = 'out.h5' /
""",
    "curve": """&chain n = 8, amplitude = 3.0, omega = 1.9, damping = 0.05, restitution = 0.5,
       spacing = 1.0 /
&run transient = 5 /
&continuation parameter = 'amplitude', stop = 2.0, step = -0.05, max_points = 8,
       follow = 'fold', parameter2 = 'omega', stop2 = 1.95, step2 = 0.01 /
&output file = 'out.h5' /
""",
    "census": """&chain n = 4, amplitude = 1.0, omega = 0.9, damping = 0.05, restitution = 0.7 /
&run transient = 50, cycles = 40, max_period = 8 /
&census samples = 4, seed = 5, x_amp = 0.3, v_amp = 1.0, exponents = 2 /
&output file = 'out.h5' /
""",
    "census_sweep": """&chain n = 4, amplitude = 1.0, omega = 0.9, damping = 0.05,
       restitution = 0.7 /
&run transient = 50, cycles = 40, max_period = 8 /
&census samples = 3, seed = 5, x_amp = 0.3, v_amp = 1.0 /
&sweep parameter = 'restitution', start = 0.7, stop = 0.8, step = 0.1 /
&output file = 'out.h5' /
""",
}


STOPPED = """&chain n = 4, amplitude = 4.15, omega = 1.5 /
&run transient = 0, cycles = 5000000, record_events = .false. /
&lyapunov enabled = .true. /
&output file = 'out.h5' /
"""


@pytest.fixture(scope="module")
def schema(impactchain_exe):
    return read_schema(impactchain_exe)


@pytest.fixture(scope="module")
def files(impactchain_exe, tmp_path_factory):
    written = {}
    for name, text in CASES.items():
        workdir = tmp_path_factory.mktemp(name)
        run_namelist(impactchain_exe, text, workdir)
        written[name] = workdir / "out.h5"
    workdir = tmp_path_factory.mktemp("stopped")
    (workdir / "in.nml").write_text(STOPPED)
    proc, _ = start_until_progress(impactchain_exe, ["in.nml"], workdir)
    proc.send_signal(signal.SIGINT)
    proc.communicate(timeout=120)
    written["stopped"] = workdir / "out.h5"
    return written


@pytest.mark.parametrize("case", sorted(CASES) + ["stopped"])
def test_every_kind_of_file_is_the_tables(schema, files, case):
    assert schema_differences(files[case], schema) == []


def test_every_optional_group_was_written(files):
    """The run of CASES holds what the table lists beyond `always` (so it is compared)."""
    with h5py.File(files["run"]) as f:
        assert {"events", "lyapunov", "finite_time", "clv", "floquet"} <= set(f)
        assert {"site_weight", "vectors"} <= set(f["clv"])
    with h5py.File(files["sweep_2d"]) as f:
        assert {"point2", "drive_period", "exponents"} <= set(f["sweep"])
    with h5py.File(files["curve"]) as f:
        assert len(f["curve/values"]) > 1
    with h5py.File(files["stopped"]) as f:
        assert f.attrs["complete"] == 0 and {"tangent", "lyapunov_int"} <= set(f["resume"])


@pytest.mark.parametrize("change", ["units", "long_name", "dims", "dtype", "missing",
                                    "model_units"])
def test_a_table_that_differs_from_the_file_is_caught(schema, files, change):
    """One entry changed in the table is one difference named (the check can fail)."""
    table = copy.deepcopy(schema)
    entry = next(e for e in table if e["path"] == "/strobe/x")
    if change == "missing":
        table.remove(entry)
    elif change == "dims":
        entry["dims"] = ["oscillator", "cycle"]
    elif change == "model_units":
        entry["model_units"] = "time"
    else:
        entry[change] = {"units": "m", "long_name": "x", "dtype": "float32"}[change]
    problems = schema_differences(files["run"], table)
    assert len(problems) == 1 and problems[0].startswith("/strobe/x: "), problems


def test_an_entry_always_written_is_required(schema, files):
    table = copy.deepcopy(schema)
    table.append(dict(next(e for e in table if e["path"] == "/strobe/x"),
                      path="/strobe/y"))
    assert schema_differences(files["run"], table) == [
        "/strobe/y: the table says a run file always holds it"]


def test_the_damping_unit_has_one_answer(schema, files):
    """b is a damping ratio (docs/model.md 1.1, 1.5): a pure number in /params and on a
    sweep's axis alike."""
    damping = next(e for e in schema if e["path"] == "/params/@damping")
    assert damping["model_units"] is None and damping["units"] == "1"
    with h5py.File(files["sweep_2d"]) as f:
        assert "model_units" not in f["sweep/point"].attrs
        assert f["sweep/point2"].attrs["model_units"] == "1/time"


@pytest.mark.parametrize("case", sorted(CASES) + ["stopped"])
def test_the_reader_names_only_the_tables_paths(files, case):
    """Every name impactchain.io and its readers read or test for is resolved in the table
    first (impactchain._hdf5._entry), so reading every kind of file, every optional group
    present, fails on a name the table lacks."""
    run = read_run(files[case])
    assert run.params.n >= 1


@pytest.mark.parametrize("path", ["/strobe/x", "/stats/@touches", "/params/@phase",
                                  "/census/sample_exponents", "/sweep/point2", "/@complete"])
def test_a_path_missing_from_the_table_fails_the_reader(files, monkeypatch, path):
    """The table without one entry: the reader stops at that name, whether the file holds
    it or not, with an error that is not the file's (no SchemaError)."""
    table = tuple(e for e in impactchain_schema._outputs() if e["path"] != path)
    monkeypatch.setattr(impactchain_schema, "_outputs", lambda: table)
    case = {"/census/sample_exponents": "census", "/sweep/point2": "sweep_2d"}.get(path, "run")
    with pytest.raises(ReaderPathError, match=f"the reader names {path}, which the file "
                                              "schema lacks"):
        read_run(files[case])


def test_a_group_missing_from_the_table_fails_the_reader(files, monkeypatch):
    table = tuple(e for e in impactchain_schema._outputs() if not e["path"].startswith("/clv/"))
    monkeypatch.setattr(impactchain_schema, "_outputs", lambda: table)
    impactchain_schema.groups.cache_clear()
    try:
        with pytest.raises(ReaderPathError, match="the reader names the group /clv, which"):
            read_run(files["run"])
    finally:
        impactchain_schema.groups.cache_clear()


def test_a_required_path_missing_from_the_table_fails(files):
    """A figure's `require` names paths of the table too: a misspelt one is no missing
    group of the file."""
    with pytest.raises(ReaderPathError, match="/strobe/xs, which the file schema lacks"):
        read_run(files["run"], require=("strobe/xs",))
    with pytest.raises(ReaderPathError, match="the group /strobes, which"):
        read_run(files["run"], require=("strobes",))
