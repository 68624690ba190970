"""Every recipe in namelists/ gives the reference values in test/recipes/reference.json,
within tolerances that follow from the physics (test/recipes/recipe_reference.py: the rules
and their reasons), on this machine's BLAS and libm kernels and on a second code path forced
in the same run. Numbers, not hashes: a check that holds on any x86-64 machine.

When a change is MEANT to alter results (a physics fix, a new default, a recipe edited or
added), this test fails by design. Then write the reference again with

    make recipe-reference

and commit it with that change, saying why the numbers moved. Never as a way to make the
test pass after a change that was supposed to keep every number: find out why they moved
first (`recipe_runs.py run` with both builds, then `compare`).

The runtime-checked build (IMPACTCHAIN_FPM_FLAGS) runs the recipes far more slowly, and its
other code paths are already covered by the second kernels, so the test is skipped there.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from file_schema import read_schema, schema_differences
from simulator import ROOT, impactchain_exe  # noqa: F401 (fixture)

SCRIPT = ROOT / "test" / "recipes" / "recipe_reference.py"
REFERENCE = ROOT / "test" / "recipes" / "reference.json"

pytestmark = pytest.mark.skipif(bool(os.environ.get("IMPACTCHAIN_FPM_FLAGS")),
                                reason="the recipes are checked with the release build")


def check(exe: Path, *args: str) -> subprocess.CompletedProcess:
    # two recipes at a time: the long sweeps (figures 13, 12 and 10) then overlap the rest
    return subprocess.run([sys.executable, str(SCRIPT), "check", "--exe", str(exe),
                           "--jobs", "2", *args], cwd=ROOT, capture_output=True, text=True,
                          timeout=3600)


@pytest.fixture(scope="module")
def machine_runs(impactchain_exe, tmp_path_factory) -> Path:
    """Every recipe run with the kernels this machine selects, and checked; the files are
    kept for the tests that check the checker."""
    runs = tmp_path_factory.mktemp("recipes") / "machine"
    result = check(impactchain_exe, "--kernels", "machine", "--keep", str(runs))
    assert result.returncode == 0, result.stdout + result.stderr
    return runs


def test_every_recipe_within_tolerance_on_this_machines_kernels(machine_runs):
    assert (machine_runs / "fig13.h5").exists()


def test_every_recipe_file_is_the_file_schemas(machine_runs, impactchain_exe):
    """Every dataset and attribute of every recipe's file is in the file schema (dims, dtype,
    units, model_units, long_name as the table has them), and each holds what the table
    says a file of its kind always holds (file_schema.py)."""
    schema = read_schema(impactchain_exe)
    files = sorted(machine_runs.glob("*.h5"))
    assert len(files) == len(list((ROOT / "namelists").glob("*.nml")))
    problems = {f.name: schema_differences(f, schema) for f in files}
    assert {name: found for name, found in problems.items() if found} == {}


def test_every_recipe_within_tolerance_on_a_second_kernel(impactchain_exe, tmp_path):
    result = check(impactchain_exe, "--kernels", "second", "--keep", str(tmp_path / "second"))
    assert result.returncode == 0, result.stdout + result.stderr


def perturbed(tmp_path: Path, recipe: str, key: str, change) -> Path:
    """A copy of the reference with one value changed by `change(entry)`."""
    reference = json.loads(REFERENCE.read_text())
    change(reference[recipe]["values"][key])
    path = tmp_path / "reference.json"
    path.write_text(json.dumps(reference))
    return path


def moved_first(factor: float, offset: float):
    """The first value times factor, plus offset."""
    def change(entry):
        values = entry["value"]
        while isinstance(values[0], list):
            values = values[0]
        values[0] = values[0]*factor + offset
    return change


@pytest.mark.parametrize("recipe, key, factor, offset, rule", [
    ("fig3_red", "/strobe/x", 1 + 1e-7, 0, "regular"),      # a periodic strobe
    ("fig10_fold", "/continuation/values", 1 + 1e-7, 0, "regular"),
    ("fig2a", "/events/site", 1, 1, "exact"),               # an event's bond
])
def test_a_value_beyond_its_tolerance_is_named(machine_runs, impactchain_exe, tmp_path,
                                               recipe, key, factor, offset, rule):
    reference = perturbed(tmp_path, recipe, key, moved_first(factor, offset))
    result = check(impactchain_exe, "--runs", str(machine_runs), "--reference", str(reference))
    assert result.returncode == 1
    lines = [line for line in result.stdout.splitlines() if line.startswith(f"{recipe}: ")]
    assert len(lines) == 1, result.stdout
    assert key in lines[0] and f"rule {rule}" in lines[0] and "tolerance" in lines[0], lines


def test_a_statistic_is_judged_by_its_standard_errors(machine_runs, impactchain_exe, tmp_path):
    """An exponent moved by 10 of its errors fails; by 1 it passes."""
    def shift(k):
        def change(entry):
            entry["value"][0] += k * entry["sigma"][0]
        return change
    for k, code in ((10.0, 1), (1.0, 0)):
        reference = perturbed(tmp_path, "fig1c_clv", "/lyapunov/exponents", shift(k))
        result = check(impactchain_exe, "--runs", str(machine_runs),
                       "--reference", str(reference))
        assert result.returncode == code, result.stdout
        if code:
            assert "/lyapunov/exponents" in result.stdout and "rule statistic" in result.stdout


def test_trajectories_are_the_same_bits_on_either_kernel(impactchain_exe, tmp_path):
    """Every function that decides a trajectory is the project's own (chain_portable_math,
    docs/model.md 2.7), so glibc's FMA and AVX2 versions of exp, sin, cos, ... and its
    baseline ones give the same chaotic run bit for bit (before, the default chain's strobe
    records differed by order one from the first recorded cycle)."""
    sys.path.insert(0, str(ROOT / "test" / "recipes"))
    from recipe_reference import MACHINE_KERNELS, SECOND_KERNELS
    from recipe_runs import RECIPES, compare_dirs, run_recipe
    for name, env in (("machine", MACHINE_KERNELS), ("second", SECOND_KERNELS)):
        (tmp_path / name).mkdir()
        run_recipe(impactchain_exe, RECIPES / "default.nml", tmp_path / name, env)
    assert compare_dirs(tmp_path / "machine", tmp_path / "second") == 0
