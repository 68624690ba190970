"""Issue 31, 6: impactchain as an fpm dependency of a project of one's own
(examples/fpm-consumer: an fpm.toml with impactchain as a path dependency and a short
program on the public API `use impactchain`) builds and runs, and its numbers obey the sum
rule of the Lyapunov spectrum."""
from __future__ import annotations

import os
import shutil
import subprocess

import pytest

from simulator import FPM, ROOT

EXAMPLE = ROOT / "examples" / "fpm-consumer"


def test_a_project_using_impactchain_builds_and_runs(tmp_path):
    if os.environ.get("IMPACTCHAIN_FPM_FLAGS"):
        pytest.skip("built once, in the release pass of the tests")
    project = tmp_path / "consumer"
    shutil.copytree(EXAMPLE, project, ignore=shutil.ignore_patterns("build"))
    # (the copy elsewhere, as a user's own project: fpm takes a path relative to the project)
    manifest = project / "fpm.toml"
    manifest.write_text(manifest.read_text().replace(
        'path = "../.."', f'path = "{os.path.relpath(ROOT, project)}"'))
    result = subprocess.run([str(FPM), "run", "--", "chain.nml"], cwd=project,
                            capture_output=True, text=True, timeout=1200)
    assert result.returncode == 0, result.stderr[-3000:]
    lines = dict(line.rsplit("  ", 1) for line in result.stdout.splitlines()
                 if line.startswith(("sum of", "-2 b n T")))
    values = [float(v) for v in lines.values()]
    assert len(values) == 2
    assert abs(values[0] - values[1]) <= 1e-9 * abs(values[1]), result.stdout
