"""Every recipe in namelists/ gives, bit for bit, the results stored in
test/recipes/checksums.json: the safety net for changes that must not alter a number
(refactors, clean-ups, a new file layout that keeps every value).

When a change is MEANT to alter results (a physics fix, a new default, a recipe edited or
added), this test fails by design. Then regenerate the manifest with

    make recipe-checksums

and commit it together with that change, saying in the commit message why the results moved.
Regenerating is a deliberate act, never a way to make this test pass after a change that was
supposed to keep every number: first find out why the numbers moved (to see where:
`python test/recipes/recipe_checksums.py check --keep DIR`, the same `compute --keep DIR_REF`
with a build of the previous commit, then `compare DIR_REF DIR`).

The manifest holds the release build's bits for one environment: the same compiler, glibc and
reference BLAS. glibc picks its own versions of sin, exp, log, ... by CPU, and the recipes'
chaotic runs magnify any last-bit difference, so the script runs the recipes with glibc's
baseline versions (GLIBC_TUNABLES), which every x86-64 CPU has. The runtime-checked
build (IMPACTCHAIN_FPM_FLAGS) computes other bits, so the test is skipped there.
"""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from simulator import ROOT, impactchain_exe  # noqa: F401 (fixture)

SCRIPT = ROOT / "test" / "recipes" / "recipe_checksums.py"

pytestmark = pytest.mark.skipif(bool(os.environ.get("IMPACTCHAIN_FPM_FLAGS")),
                                reason="the manifest holds the release build's bits")


def test_every_recipe_gives_the_stored_checksums(impactchain_exe):
    # two recipes at a time: the two long sweeps (figures 13 and 10) then overlap the rest
    result = subprocess.run(
        [sys.executable, str(SCRIPT), "check", "--exe", str(impactchain_exe), "--jobs", "2"],
        cwd=ROOT, capture_output=True, text=True, timeout=1800,
    )
    assert result.returncode == 0, result.stdout + result.stderr
