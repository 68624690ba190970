"""Issue 31, 1: the folders of src/ are layers whose `use`s point one way
(test/check_layers.py); a back-edge fails the check, naming the file, the module and both
layers, and so does a folder of tests named like no layer."""
from __future__ import annotations

import shutil
import subprocess
import sys

from simulator import ROOT

CHECKER = ROOT / "test" / "check_layers.py"


def _check(root) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(CHECKER), str(root)], capture_output=True,
                          text=True, timeout=60)


def test_the_tree_has_no_back_edge():
    result = _check(ROOT)
    assert result.returncode == 0, result.stderr


def test_a_back_edge_fails(tmp_path):
    shutil.copytree(ROOT / "src", tmp_path / "src")
    flow = tmp_path / "src" / "model" / "chain_flow.f90"
    # the model made to use the engine, which stands above it
    flow.write_text(flow.read_text().replace("    use chain_kinds,",
                                             "    use chain_engine, only: chain_t\n"
                                             "    use chain_kinds,", 1))
    (tmp_path / "app").mkdir()
    (tmp_path / "app" / "main.f90").write_text("program p\n    use chain_sim\nend program p\n")
    result = _check(tmp_path)
    assert result.returncode == 1
    lines = result.stderr.splitlines()
    assert ("check_layers: src/model/chain_flow.f90: uses chain_engine (layer engine), which "
            "layer model may not use (it may use: base)") in lines, lines
    assert any(line.startswith("check_layers: app/main.f90: uses chain_sim (layer runs)")
               for line in lines), lines
    assert len(lines) == 2


def test_a_source_outside_the_layers_fails(tmp_path):
    shutil.copytree(ROOT / "src", tmp_path / "src")
    (tmp_path / "src" / "chain_loose.f90").write_text("module chain_loose\nend module\n")
    (tmp_path / "src" / "extra").mkdir()
    (tmp_path / "src" / "extra" / "chain_extra.c").write_text("int x;\n")
    result = _check(tmp_path)
    assert result.returncode == 1
    assert [line.split(":")[1].strip() for line in result.stderr.splitlines()] == [
        "src/chain_loose.f90", "src/extra/chain_extra.c"], result.stderr


def test_a_test_area_named_like_no_layer_fails(tmp_path):
    """test/ mirrors src/ (test/README.md): a folder of tests is named like the layer it
    tests; the Fortran area test/model passes, test/physics and test/python/output do not."""
    shutil.copytree(ROOT / "src", tmp_path / "src")
    for source in ("test/support/src/testing.f90", "test/model/test_gaps.f90", "test/physics/test_flow.f90",
                   "test/python/test_cli.py", "test/python/output/test_file.py",
                   "test/python/package/test_io.py"):
        (tmp_path / source).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / source).write_text("\n")
    result = _check(tmp_path)
    assert result.returncode == 1
    assert [line.split(":")[1].strip() for line in result.stderr.splitlines()] == [
        "test/physics", "test/python/output"], result.stderr
    assert "a test area with no folder src/physics" in result.stderr
