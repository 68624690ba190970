"""Every shell command of the pages (docs/*.md, README.md) is run by a test, or marked as
covered by another test, or says why no test runs it.

The convention (docs/README.md): shell commands are written in ```sh blocks, each preceded by
one of
    <!-- commands: run by test/docs/test_commands.py -->    run here: a page's blocks in order
    <!-- commands: run by PATH -->                           a test that reads this page and
                                                           runs the block as written
    <!-- commands: covered by PATH::TEST -->                 a test that runs the same commands
    <!-- commands: not run by a test: REASON -->            (set-up, hours-long runs)
and what a program prints goes in ```console blocks (or plain ``` blocks), which are not run.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
THIS = "test/docs/test_commands.py"
PAGES = sorted([*ROOT.glob("docs/*.md"), ROOT / "README.md"])
SHELL_FENCE = re.compile(r"^```(?:sh|bash|shell)\s*$", re.M)
MARKED = re.compile(r"<!-- commands: (.+?) -->\n```(?:sh|bash|shell)\n(.*?)^```", re.M | re.S)
# what a page's commands need in their scratch directory before they run
WITHOUT_OUTPUT = ("awk '/^&output/{skip=1} !skip{print} skip&&/^\\//{skip=0}' "
                  "\"$ROOT/namelists/default.nml\"")
SETUP = {
    "docs/figures.md": WITHOUT_OUTPUT + " > run.nml && "
                       "impactchain --quiet --set run.cycles=60 run.nml && "
                       "impactchain --quiet -o sweep.h5 --set sweep.start=3.0 --set sweep.stop=2.5 "
                       "--set sweep.step=-0.1 --set run.transient=20 --set run.cycles=40 "
                       "--set lyapunov.enabled=.true. \"$ROOT/namelists/fig10.nml\" && "
                       "impactchain --quiet -o cont.h5 \"$ROOT/namelists/fig10_free.nml\" && "
                       "impactchain --quiet -o fold.h5 --set continuation.max_points=8 "
                       "\"$ROOT/gallery/charts/chart_fig10_fold_up.nml\" && "
                       "impactchain --quiet -o grazing.h5 --set continuation.max_points=10 "
                       "\"$ROOT/gallery/charts/chart_fig10_grazing_down.nml\" && "
                       "impactchain --quiet -o map.h5 --set sweep.start=3.0 --set sweep.stop=2.6 "
                       "--set sweep.step=-0.2 --set sweep.start2=1.88 --set sweep.stop2=1.92 "
                       "--set sweep.step2=0.02 --set run.transient=5 --set run.cycles=6 "
                       "\"$ROOT/gallery/charts/chart_fig10_map.nml\"",
    "docs/running.md": WITHOUT_OUTPUT + " > input.nml",
    "docs/orbits.md": "mkdir -p figures/runs && impactchain --quiet -o figures/runs/fig10.h5 "
                      "--set sweep.start=3.5 --set sweep.step=-0.05 --set run.transient=100 "
                      "--set run.cycles=20 \"$ROOT/namelists/fig10.nml\"",
}


def _blocks(page: Path) -> list[tuple[str, str]]:
    return MARKED.findall(page.read_text(encoding="utf-8"))


def _name(page: Path) -> str:
    return page.relative_to(ROOT).as_posix()


def _run_here() -> list[tuple[str, str]]:
    """Each page's blocks to run here, in the page's order, as one script."""
    found = []
    for page in PAGES:
        blocks = [block for mark, block in _blocks(page) if mark == f"run by {THIS}"]
        if blocks:
            found.append((_name(page), "".join(blocks)))
    return found


@pytest.mark.parametrize("page", PAGES, ids=_name)
def test_every_shell_block_is_marked(page: Path) -> None:
    text = page.read_text(encoding="utf-8")
    assert len(SHELL_FENCE.findall(text)) == len(_blocks(page)), (
        f"{_name(page)}: a ```sh block without its <!-- commands: ... --> line")


@pytest.mark.parametrize("page", PAGES, ids=_name)
def test_every_mark_names_a_test_that_runs_it(page: Path) -> None:
    for mark, block in _blocks(page):
        if mark == f"run by {THIS}":
            continue
        if mark.startswith("run by "):
            runner = ROOT / mark.removeprefix("run by ")
            assert runner.is_file(), f"{_name(page)}: {mark}: no such file"
            assert _name(page) in runner.read_text(), (
                f"{_name(page)}: {mark}, which never reads {_name(page)}")
        elif mark.startswith("covered by "):
            path, _, test = mark.removeprefix("covered by ").partition("::")
            assert (ROOT / path).is_file(), f"{_name(page)}: {mark}: no such file"
            assert re.search(rf"^def {re.escape(test)}\(", (ROOT / path).read_text(), re.M), (
                f"{_name(page)}: {mark}: no such test")
        else:
            assert re.fullmatch(r"not run by a test: \S.{10,}", mark), (
                f"{_name(page)}: unknown mark '{mark}' before:\n{block}")


@pytest.mark.parametrize("page, commands", _run_here(), ids=[p for p, _ in _run_here()])
def test_commands_run_as_written(page: str, commands: str, tmp_path: Path) -> None:
    """A page's blocks in order, each command to succeed, in a scratch directory that has the
    environment as .venv (so that `source .venv/bin/activate` and `.venv/bin/python` work as
    on the page) and its programs on PATH."""
    venv = ROOT / ".venv"
    (tmp_path / ".venv").symlink_to(venv)
    env = {**os.environ, "ROOT": str(ROOT), "PATH": f"{venv / 'bin'}:{os.environ['PATH']}",
           "MPLBACKEND": "Agg"}
    script = f"set -euo pipefail\n{SETUP.get(page, '')}\n{commands}"
    done = subprocess.run(["bash", "-c", script], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, f"{page}: {commands}\n{done.stdout}\n{done.stderr}"


def test_a_block_without_its_mark_is_found(tmp_path: Path) -> None:
    page = tmp_path / "page.md"
    page.write_text("<!-- commands: run by x -->\n```sh\nls\n```\n\n```sh\nrm -rf /\n```\n")
    assert len(SHELL_FENCE.findall(page.read_text())) == 2 and len(_blocks(page)) == 1
    assert shutil.which("bash")
