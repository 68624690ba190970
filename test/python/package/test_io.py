"""impactchain.io: reading the schema_version 1 layout (the synthetic files of conftest) and
rejecting what is not; test_io_versions.py reads the simulator's own files of versions 1 and 2."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import h5py
import numpy as np
import pytest

from conftest import PERIODS, cascade_events, lyapunov_spectrum, strobe_record, sweep_values
from conftest import DEFAULT_SWEEP, clv_exponents, clv_min_angles, clv_weights
from impactchain.io import (FILE_UNITS, IN_MEMORY, SchemaError, namelist_groups, read_run,
                            run_from_api)

MakeRun = Callable[..., Path]


def test_reads_params_and_geometry(make_run: MakeRun) -> None:
    spacing = np.array([1.0, 0.9, 1.1, 1.0, 1.2])
    run = read_run(make_run(spacing=spacing, phase=0.5 * math.pi))
    p = run.params
    assert (p.n, p.boundary, p.walls) == (4, "fixed", True)
    assert p.omega == 1.5 and p.drive_period == pytest.approx(2 * math.pi / 1.5)
    np.testing.assert_array_equal(p.spacing, spacing)
    np.testing.assert_allclose(p.equilibrium, [1.0, 1.9, 3.0, 4.0])
    np.testing.assert_allclose(p.site_positions, [0.0, 1.0, 1.9, 3.0, 4.0])
    assert p.length == pytest.approx(5.2)
    assert p.section_offset == pytest.approx(0.25)


def test_reads_root_attributes_and_padded_strings(make_run: MakeRun) -> None:
    run = read_run(make_run(boundary="free"))
    assert run.schema_version == 1
    assert run.code_version == "0.1.0"
    assert run.input_namelist.startswith("&chain")
    assert run.complete is True
    assert run.params.boundary == "free" and not run.params.walls
    assert run.name == "run"


def test_reads_strobe_with_records_first(make_run: MakeRun) -> None:
    run = read_run(make_run(n=5, records=12, first_cycle=40))
    assert run.strobe is not None
    np.testing.assert_array_equal(run.strobe.x, strobe_record(5, 12))
    assert run.strobe.x.shape == (12, 5) and run.strobe.n_record == 12
    np.testing.assert_array_equal(run.strobe.cycle, np.arange(40, 52))
    np.testing.assert_array_equal(run.strobe.period, [PERIODS[i % 4] for i in range(5)])
    assert run.unit("strobe/x") == "a" and run.unit("/strobe/x") == "a"
    assert run.unit("nowhere", "m") == "m"


def test_reads_events_stats_final_and_lyapunov(make_run: MakeRun) -> None:
    run = read_run(make_run(n=3, records=4, lyapunov=True))
    time, site, _, _ = cascade_events(3, np.arange(100, 104), run.params.drive_period)
    assert run.events is not None and run.stats is not None and run.lyapunov is not None
    np.testing.assert_array_equal(run.events.time, time)
    np.testing.assert_array_equal(run.events.site, site)
    assert run.events.collisions.all()
    assert run.stats.site_counts.shape == (4,) and run.stats.impacts == 60
    assert run.final is not None and run.final.cycle == 104 and run.final.phase == 0.0
    np.testing.assert_array_equal(run.lyapunov.exponents, lyapunov_spectrum(3))
    assert run.lyapunov.running.shape == (4, 6)
    assert run.lyapunov.ky_dimension == 3.5


def test_reads_cycles_done_of_a_stopped_run(make_run: MakeRun) -> None:
    path = make_run(n=3, records=4, complete=0)
    assert read_run(path).stats.cycles_done is None  # a file from before it was recorded
    with h5py.File(path, "r+") as f:
        f["stats/cycles_done"] = np.int64(4)
    run = read_run(path)
    assert not run.complete and run.stats.cycles_done == 4


def test_reads_sweep(make_run: MakeRun) -> None:
    run = read_run(make_run(strobe=False, events=False, sweep=True))
    sweep = run.sweep
    assert sweep is not None and run.strobe is None and run.events is None
    assert (sweep.parameter, sweep.parameter2, sweep.mode) == ("amplitude", "", "down")
    assert not sweep.is_2d
    np.testing.assert_array_equal(sweep.values, sweep_values(DEFAULT_SWEEP))
    assert sweep.x.shape == (7, 5, 4)
    assert sweep.exponents is not None and sweep.exponents.shape == (7, 6)
    assert sweep.ky_dimension is not None


def test_reads_two_parameter_sweep(make_run: MakeRun) -> None:
    run = read_run(make_run(sweep={"parameter2": "omega"}))
    assert run.sweep is not None and run.sweep.is_2d
    assert run.sweep.values.shape == (7, 2)


def test_arrays_are_read_only_and_dataclasses_frozen(make_run: MakeRun) -> None:
    run = read_run(make_run())
    assert run.strobe is not None
    with pytest.raises(ValueError):
        run.strobe.x[0, 0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        run.params.n = 3  # type: ignore[misc]


def test_groups_limits_what_is_loaded(make_run: MakeRun) -> None:
    run = read_run(make_run(lyapunov=True), groups=("strobe",))
    assert run.strobe is not None
    assert run.events is None and run.lyapunov is None


def test_incomplete_run_is_flagged(make_run: MakeRun) -> None:
    assert read_run(make_run(complete=0)).complete is False


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(SchemaError, match="no such file"):
        read_run(tmp_path / "absent.h5")


def test_not_hdf5(tmp_path: Path) -> None:
    path = tmp_path / "text.h5"
    path.write_text("not an HDF5 file\n")
    with pytest.raises(SchemaError, match="not an HDF5 file"):
        read_run(path)


def test_schema_error_is_a_value_error() -> None:
    assert issubclass(SchemaError, ValueError)


def test_wrong_schema_version(make_run: MakeRun) -> None:
    with pytest.raises(SchemaError, match="schema_version 3 is not supported"):
        read_run(make_run(schema_version=3))


def test_missing_schema_version(make_run: MakeRun) -> None:
    with pytest.raises(SchemaError, match="no 'schema_version' attribute"):
        read_run(make_run(schema_version=None))


def test_required_group_missing(make_run: MakeRun) -> None:
    path = make_run(events=False)
    with pytest.raises(SchemaError, match=r"no /events, needed by shock-wave \(events were"):
        read_run(path, require=("events",), purpose="shock-wave")


def test_required_alternatives(make_run: MakeRun) -> None:
    path = make_run(sweep={"exponents": 0})
    with pytest.raises(SchemaError, match="no /sweep/ky_dimension or /sweep/exponents"):
        read_run(path, require=("sweep/ky_dimension|sweep/exponents",))
    path = make_run("ok.h5", sweep={"ky_dimension": False})
    assert read_run(path, require=("sweep/ky_dimension|sweep/exponents",)).sweep is not None


def test_transposed_strobe_is_rejected(make_run: MakeRun) -> None:
    with pytest.raises(SchemaError, match="axes transposed"):
        read_run(make_run(n=4, records=9, transpose_strobe=True))


def test_wrong_spacing_length(make_run: MakeRun) -> None:
    path = make_run()
    with h5py.File(path, "r+") as f:
        del f["params/spacing"]
        f["params"].create_dataset("spacing", data=np.ones(3))
    with pytest.raises(SchemaError, match=r"/params/spacing has shape \(3,\), expected \(5\)"):
        read_run(path)


def test_missing_parameter_attribute(make_run: MakeRun) -> None:
    path = make_run()
    with h5py.File(path, "r+") as f:
        del f["params"].attrs["omega"]
    with pytest.raises(SchemaError, match="/params lacks attribute 'omega'"):
        read_run(path)


def test_event_site_out_of_range(make_run: MakeRun) -> None:
    path = make_run(n=3, events={"time": [0.1, 0.2], "site": [0, 7]})
    with pytest.raises(SchemaError, match="outside 0..3"):
        read_run(path)


# ------------------------------------------------------------------- covariant vectors


def test_reads_clv_with_records_first(make_run: MakeRun) -> None:
    run = read_run(make_run(n=4, records=30, first_cycle=40, lyapunov=True,
                            clv={"transient": 10, "store": 3, "save": 2, "unstable": 1}))
    clv = run.clv
    assert clv is not None
    assert (clv.n_record, clv.k, clv.stored, clv.unstable, clv.clv_transient) == (20, 8, 3, 1, 10)
    np.testing.assert_array_equal(clv.cycle, np.arange(40, 60))
    np.testing.assert_array_equal(clv.exponents, clv_exponents(4))
    assert clv.stderr.shape == (8,) and clv.stderr_block.dtype == np.int64
    assert clv.site_weight is not None and clv.site_weight.shape == (20, 3, 4)
    np.testing.assert_array_equal(clv.site_weight, clv_weights(4, 20, 3))
    assert clv.ipr.shape == (20, 8)
    np.testing.assert_allclose(clv.ipr[:, :3], (clv.site_weight ** 2).sum(axis=2))
    np.testing.assert_array_equal(clv.min_angle, clv_min_angles(20))
    assert clv.vectors is not None and clv.vectors.shape == (2, 8, 8)
    assert clv.saved_cycle is not None and clv.saved_cycle.tolist() == [58, 59]
    assert run.unit("clv/exponents") == "bits per drive cycle"
    assert run.unit("clv/min_angle") == "radian"
    with pytest.raises(ValueError):
        clv.ipr[0, 0] = 1.0


def test_clv_without_site_weights_or_vectors(make_run: MakeRun) -> None:
    run = read_run(make_run(clv={"store": 0, "save": 0}))
    assert run.clv is not None and run.clv.stored == 0
    assert run.clv.site_weight is None and run.clv.vectors is None and run.clv.saved_cycle is None
    with pytest.raises(SchemaError, match=r"no /clv/site_weight, needed by clv-space-time "
                                          r"\(the run stored no site weights"):
        read_run(run.path, require=("clv/site_weight",), purpose="clv-space-time")
    assert read_run(make_run("plain.h5")).clv is None
    with pytest.raises(SchemaError, match=r"no /clv, needed by clv-ipr \(covariant Lyapunov "
                                          "vectors were not computed"):
        read_run(make_run("plain.h5"), require=("clv",), purpose="clv-ipr")


def _edit_clv(path: Path, edit: Callable[[h5py.Group], None]) -> Path:
    with h5py.File(path, "r+") as f:
        edit(f["clv"])
    return path


def _replace(name: str, data: Any) -> Callable[[h5py.Group], None]:
    def edit(g: h5py.Group) -> None:
        del g[name]
        g[name] = data
    return edit


@pytest.mark.parametrize(("edit", "message"), [
    (lambda g: g.__delitem__("ipr"), "no /clv/ipr dataset"),
    (lambda g: g.__delitem__("stderr_block"), "no /clv/stderr_block dataset"),
    (lambda g: g.attrs.__delitem__("unstable"), "/clv lacks attribute 'unstable'"),
    (lambda g: g.attrs.__delitem__("clv_transient"), "/clv lacks attribute 'clv_transient'"),
    (lambda g: g.__delitem__("vectors"), "no /clv/vectors dataset"),
    (lambda g: g.attrs.__setitem__("unstable", 9), "/clv@unstable = 9 is outside 0..8"),
    (_replace("ipr", np.zeros((8, 20))), r"/clv/ipr has shape \(8, 20\), expected \(20, 8\) "
                                         r"\(axes transposed"),
    (_replace("min_angle", np.zeros(19)), r"/clv/min_angle has shape \(19,\), expected \(20\)"),
    (_replace("site_weight", np.zeros((20, 2, 5))), r"/clv/site_weight has shape \(20, 2, 5\), "
                                                    r"expected \(20, \*, 4\)"),
    (_replace("site_weight", np.zeros((20, 9, 4))), "holds 9 vectors, more than the 8"),
    (_replace("vectors", np.zeros((1, 8, 4))), r"/clv/vectors has shape \(1, 8, 4\), "
                                               r"expected \(1, 8, 8\)"),
])
def test_clv_schema_errors_name_what_is_wrong(make_run: MakeRun, edit: Callable[[h5py.Group],
                                              None], message: str) -> None:
    path = _edit_clv(make_run(n=4, records=30, clv=True), edit)
    with pytest.raises(SchemaError, match=message):
        read_run(path)
    assert read_run(path, groups=("strobe",)).clv is None  # not loaded, not checked


# ------------------------------------------------------------------------- namelists


def test_reads_the_resolved_namelist(make_run: MakeRun) -> None:
    run = read_run(make_run(seed=4))
    assert run.resolved_namelist.startswith("&chain n = 4")
    assert run.namelist()["initial"] == {"kind": "'random'", "seed": "4",
                                         "x_amp": "0.300000000000000",
                                         "v_amp": "1.00000000000000"}
    older = read_run(make_run("older.h5"))  # no resolved_namelist: the input text
    assert older.resolved_namelist == "" and older.namelist() == {"chain": {"n": "4"}}


def test_namelist_groups_reads_the_input_syntax() -> None:
    text = """! a comment with &fake key = 1 /
&chain n = 3, spacing = 1.0, 0.9, 1.1,
       1.0   ! per bond
       boundary = 'fixed' /
&output file = 'a b=c/d!e.h5', overwrite = .true. /
&initial kind = "random",
  seed = 7
/
"""
    groups = namelist_groups(text)
    assert groups == {
        "chain": {"n": "3", "spacing": "1.0, 0.9, 1.1,\n       1.0", "boundary": "'fixed'"},
        "output": {"file": "'a b=c/d!e.h5'", "overwrite": ".true."},
        "initial": {"kind": '"random"', "seed": "7"},
    }


# ---------------------------------------------------------------------- in-memory runs


def _api_like(n: int = 3, cycles: int = 5) -> tuple[SimpleNamespace, SimpleNamespace]:
    """Stand-ins with the fields of impactchain.api.Simulation and impactchain.api.Lyapunov."""
    params = dict(n=n, amplitude=1.7, omega=1.5, damping=0.05, restitution=0.7,
                  spacing=np.ones(n + 1), boundary="fixed", x0=np.full(n, 0.1),
                  v0=np.zeros(n), transient=10, cycles=cycles, phase=0.0,
                  stick_speed=1e-9, events=True, code_version="impactchain.api 0.1.0")
    sim = SimpleNamespace(
        x=np.arange(cycles * n, dtype=float).reshape(cycles, n), v=np.zeros((cycles, n)),
        cycle=np.arange(11, 11 + cycles), periods=np.array([1, 2, 0][:n] * (n // 3 + 1))[:n],
        event_time=np.array([0.5, 0.7]), event_site=np.array([0, 1]),
        event_speed=np.array([1.0, 2.0]), event_kind=np.array([0, 0]),
        final_x=np.full(n, 0.2), final_v=np.zeros(n), site_counts=np.ones(n + 1),
        impacts=2, sticks=0, releases=0, touches=0, collisions_per_cycle=0.4,
        params=params)
    lyap = SimpleNamespace(
        exponents=np.linspace(0.1, -1.0, 2 * n), stderr=np.full(2 * n, 0.01),
        exponents_per_time=np.linspace(0.1, -1.0, 2 * n) / 3, ky_dimension=2.5,
        collisions_per_cycle=0.4, final_x=np.full(n, 0.2), final_v=np.zeros(n),
        params={**params, "events": False, "vectors": 0, "qr_every": 1})
    return sim, lyap


def test_run_from_api_is_the_run_the_file_would_hold() -> None:
    sim, lyap = _api_like()
    run = run_from_api(sim, lyap)
    assert run.path == IN_MEMORY and run.complete and run.units == FILE_UNITS
    assert run.code_version == "impactchain.api 0.1.0"
    p = run.params
    assert (p.n, p.amplitude, p.omega, p.boundary, p.transient, p.cycles) == (
        3, 1.7, 1.5, "fixed", 10, 5)
    assert p.drive_period == pytest.approx(2 * math.pi / 1.5)
    assert run.strobe is not None and run.events is not None and run.lyapunov is not None
    np.testing.assert_array_equal(run.strobe.x, sim.x)
    np.testing.assert_array_equal(run.strobe.period, sim.periods)
    np.testing.assert_array_equal(run.events.site, [0, 1])
    np.testing.assert_array_equal(run.lyapunov.stderr, lyap.stderr)
    assert run.lyapunov.running.shape == (0, 6) and math.isnan(run.lyapunov.positive_sum)
    assert run.initial is not None and run.initial.x.tolist() == [0.1, 0.1, 0.1]
    assert run.final is not None and run.final.cycle == 15
    with pytest.raises(ValueError):
        run.strobe.x[0, 0] = 1.0
    groups = run.namelist()
    assert groups["chain"]["amplitude"] == "1.7" and groups["initial"]["kind"] == "'explicit'"
    assert groups["run"]["cycles"] == "5" and groups["lyapunov"]["enabled"] == ".true."


def test_run_from_api_refuses_mismatched_or_foreign_results() -> None:
    sim, lyap = _api_like()
    lyap.params["omega"] = 1.6
    with pytest.raises(ValueError, match="differ in omega"):
        run_from_api(sim, lyap)
    with pytest.raises(ValueError, match="not an impactchain.api result"):
        run_from_api(SimpleNamespace(x=np.zeros((1, 1))))
    with pytest.raises(ValueError, match="needs a simulation"):
        run_from_api()
