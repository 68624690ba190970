"""The package as installed: pytest runs against the installation, and ``pip install`` of the
repository builds a working extension in a fresh environment.

``test_imports_the_installed_package`` (always): ``impactchain`` comes from site-packages, not
from python/impactchain/ of the source tree, its Python files are those of the tree (an
install that is out of date says so here rather than by failing elsewhere), and the compiled
extension sits next to them.

``test_pip_install_in_a_fresh_venv`` (marker ``install``, a full build of a few minutes:
``pytest -m install``; ``make test`` runs it once): ``pip install <repository>`` in a new
virtual environment, then, from a directory outside the repository, ``import impactchain``
finds the extension, ``python -m impactchain --help`` works, and a short simulation gives
the same bits as the extension of the environment running the tests.
"""

from __future__ import annotations

import importlib.metadata
import os
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

import impactchain
from impactchain import _calls, api

ROOT = Path(__file__).resolve().parents[3]
SOURCE = ROOT / "python" / "impactchain"
PROBE = ("import sys, impactchain; "
         "assert impactchain.api.extension_available(), 'no extension'; "
         "print(impactchain.__file__); "
         "print(impactchain.api.simulate(6, 1.7, 1.5, transient=10, cycles=20).x.tobytes().hex())")


def test_imports_the_installed_package() -> None:
    installed = Path(impactchain.__file__).resolve().parent
    assert installed != SOURCE, (
        "impactchain is imported from the source tree; install it (`make build` or "
        "`pip install .`) and keep python/ off sys.path")
    assert not installed.is_relative_to(ROOT / "python")
    assert importlib.metadata.version("impactchain") == impactchain.__version__
    sources = [p.relative_to(SOURCE) for p in sorted(SOURCE.rglob("*.py"))]
    stale = [str(p) for p in sources
             if not (installed / p).is_file()
             or (installed / p).read_bytes() != (SOURCE / p).read_bytes()]
    assert not stale, (f"the installed impactchain ({installed}) is out of date: {stale} "
                       "differ from python/impactchain/; run `make build` (or `pip install .`)")
    if api.extension_available() or "IMPACTCHAIN_REQUIRE_EXTENSION" in os.environ:
        assert api.extension_available()
        assert Path(_calls._kernels.__file__).resolve().parent == installed


def test_bare_import_reaches_every_module() -> None:
    """``import impactchain`` then ``impactchain.api`` etc. (imported on first use)."""
    modules = [p.stem for p in SOURCE.glob("*.py")]
    packages = [p.name for p in SOURCE.iterdir() if (p / "__init__.py").is_file()]
    names = sorted(name for name in modules + packages if not name.startswith("_"))
    assert names == sorted(impactchain._SUBMODULES)
    for name in names:
        assert getattr(impactchain, name).__name__ == f"impactchain.{name}"
    with pytest.raises(AttributeError):
        impactchain.no_such_module  # noqa: B018


def _clean_env() -> dict[str, str]:
    """The environment without this venv's traces, so that the new one stands alone."""
    env = {k: v for k, v in os.environ.items()
           if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME", "PIP_REQUIRE_VIRTUALENV")}
    venv_bin = str(Path(sys.prefix) / "bin")
    env["PATH"] = os.pathsep.join(p for p in env.get("PATH", "").split(os.pathsep)
                                  if p and p != venv_bin)
    env["PIP_DISABLE_PIP_VERSION_CHECK"] = "1"
    env["MPLBACKEND"] = "Agg"
    return env


def _run(cmd: list[str | Path], cwd: Path, env: dict[str, str],
         timeout: float) -> subprocess.CompletedProcess[str]:
    result = subprocess.run([str(c) for c in cmd], cwd=cwd, env=env, capture_output=True,
                            text=True, timeout=timeout, check=False)
    assert result.returncode == 0, (f"{' '.join(map(str, cmd))} failed:\n"
                                    f"{result.stdout[-6000:]}\n{result.stderr[-6000:]}")
    return result


@pytest.mark.install
def test_pip_install_in_a_fresh_venv(tmp_path: Path) -> None:
    env = _clean_env()
    venv = tmp_path / "venv"
    outside = tmp_path / "elsewhere"
    outside.mkdir()
    start = time.monotonic()
    _run([sys.executable, "-m", "venv", venv], tmp_path, env, 300)
    python = venv / "bin" / "python"
    _run([python, "-m", "pip", "install", "--quiet", ROOT], outside, env, 1800)
    built = time.monotonic() - start

    probe = _run([python, "-c", PROBE], outside, env, 300).stdout.split()
    assert Path(probe[0]).resolve().is_relative_to(venv.resolve()), probe[0]
    here = api.simulate(6, 1.7, 1.5, transient=10, cycles=20).x.tobytes().hex()
    assert probe[1] == here, "the fresh build computes other bits than the installed one"

    usage = _run([python, "-m", "impactchain", "--help"], outside, env, 300).stdout
    assert usage.startswith("usage: python -m impactchain")

    # the simulator on the PATH the install gives (issue 32, 4): from another directory, its
    # file next to the input, the same records as the package's kernels
    inputs = tmp_path / "inputs"
    inputs.mkdir()
    (inputs / "small.nml").write_text("&chain n = 6, amplitude = 1.7, omega = 1.5 /\n"
                                      "&run transient = 10, cycles = 20 /\n")
    path_env = {**env, "PATH": f"{venv / 'bin'}{os.pathsep}{env.get('PATH', '')}"}
    ran = _run(["impactchain", "--quiet", "../inputs/small.nml"], outside, path_env, 300)
    assert "wrote ../inputs/small.h5" in ran.stdout
    with h5py.File(inputs / "small.h5") as f:
        records = f["strobe/x"][()]
    assert np.array_equal(records, api.simulate(6, 1.7, 1.5, transient=10, cycles=20).x)
    print(f"fresh venv + pip install of the repository: {built:.0f} s")
