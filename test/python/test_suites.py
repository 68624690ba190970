"""Named Fortran test suites (test/support/src/suites.f90): `fpm test -- <suite> ...` runs
exactly the named suites across the test programs (one per layer, fpm.toml's [[test]]),
`--list` names them all, an unknown name is an error.

Runs `fpm test` itself (the release build, or the build with IMPACTCHAIN_FPM_FLAGS), on the
quick suites only; `make test` runs every suite.
"""
from __future__ import annotations

import os
import re
import subprocess
import tomllib

from simulator import FPM, ROOT

SUITE_LINE = re.compile(r"^  (\S+) checks: (\d+) passed, (\d+) failed$")
COUNT_LINE = re.compile(r"^(\d+) passed, (\d+) failed")
LIST_LINE = re.compile(r"^([a-z][a-z0-9]*) +([\w-]+)$")
#: the test programs, one per layer of src/ with suites
PROGRAMS = [test["name"] for test in tomllib.loads((ROOT / "fpm.toml").read_text())["test"]]


def fpm_test(*args: str) -> subprocess.CompletedProcess[str]:
    flags = os.environ.get("IMPACTCHAIN_FPM_FLAGS")
    profile = ["--flag", flags] if flags else ["--profile", "release"]
    return subprocess.run([str(FPM), "test", *profile, "--", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=1800, check=False)


def suites_run(stdout: str) -> list[str]:
    return [m.group(1) for line in stdout.splitlines() if (m := SUITE_LINE.match(line))]


def counts(stdout: str) -> list[str]:
    return [line for line in stdout.splitlines() if COUNT_LINE.match(line)]


def valid_names() -> list[str]:
    """The names the programs accept, from the error message of an unknown one."""
    result = fpm_test("no-such-suite")
    assert result.returncode != 0
    messages = [line for line in (result.stdout + result.stderr).splitlines()
                if "unknown test suite 'no-such-suite'" in line]
    assert len(messages) == len(PROGRAMS), result.stdout + result.stderr  # one per program
    names = messages[0].split("the suites are:")[1].split("(")[0].split()
    assert all(m.split("the suites are:")[1] == messages[0].split("the suites are:")[1]
               for m in messages)
    return names


def test_unknown_suite_is_an_error_listing_the_valid_names() -> None:
    names = valid_names()
    assert {"flow", "lyapunov", "invariants", "sweep", "checkpoint"} <= set(names)
    assert len(names) == len(set(names))


def test_list_names_every_suite_once_with_its_program() -> None:
    result = fpm_test("--list")
    assert result.returncode == 0, result.stdout + result.stderr
    listed = [m.groups() for line in result.stdout.splitlines() if (m := LIST_LINE.match(line))]
    names = [name for name, _ in listed]
    # every name the programs accept is run by exactly one of them, and no other
    assert sorted(names) == sorted(valid_names())
    assert {program for _, program in listed} == set(PROGRAMS)
    assert dict(listed)["sweep"] == dict(listed)["checkpoint"] != dict(listed)["flow"]
    assert suites_run(result.stdout) == [] and counts(result.stdout) == []


def test_named_suites_run_alone_in_each_program() -> None:
    result = fpm_test("queue", "checkpoint", "queue")
    assert result.returncode == 0, result.stdout + result.stderr
    assert sorted(suites_run(result.stdout)) == ["checkpoint", "queue"]
    lines = counts(result.stdout)
    assert len(lines) == len(PROGRAMS)  # one "N passed, M failed" per program
    ran = [line for line in lines if not line.startswith("0 passed, 0 failed")]
    assert len(ran) == 2  # the programs of the queue and of the checkpoint suite
    assert all(int(COUNT_LINE.match(line).group(1)) > 0 for line in ran)
    assert all(COUNT_LINE.match(line).group(2) == "0" for line in lines)


def test_a_program_without_a_named_suite_runs_nothing_and_says_so() -> None:
    result = fpm_test("queue")
    assert result.returncode == 0, result.stdout + result.stderr
    assert suites_run(result.stdout) == ["queue"]
    lines = counts(result.stdout)
    assert len(lines) == len(PROGRAMS)
    idle = [line for line in lines if line.startswith("0 passed, 0 failed")]
    assert len(idle) == len(PROGRAMS) - 1
    assert all("none of the named suites is in" in line for line in idle)
    assert any("sweep checkpoint" in line for line in idle)
    assert result.stdout.rstrip().splitlines()[-1] in lines  # the counts come last
