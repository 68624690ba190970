"""Build the Python extension ``post._kernels`` from a fresh clone.

Usage (from anywhere; the venv's python, so that numpy, meson and ninja are found)::

    .venv/bin/python f2py/build.py           # skips the build when the .so is up to date
    .venv/bin/python f2py/build.py --force   # always rebuild

Steps, in a temporary directory:

1. compile every library source in ``src/`` and the support module ``f2py/chain_bridge.f90``
   with gfortran and exactly the flags of ``fpm build --profile release`` (see
   ``RELEASE_FLAGS``): the extension then runs the same machine code as the CLI, which is
   what makes Python and ``fpm run --profile release`` results bit-identical;
2. generate the f2py signature file from the thin layer alone
   (``f2py -m _kernels impactchain_f2py.f90 -h _kernels.pyf only: ic_run ...``), so that f2py
   wraps only the layer's three plain subroutines and never sees a derived type;
3. ``python -m numpy.f2py -c --backend meson`` on the signature and the layer, linking the
   library objects, HDF5 (``chain_sim`` uses ``chain_output``), LAPACK and BLAS;
4. move ``_kernels.<python tag>.so`` into ``post/`` (atomic rename: a running Python that has
   the old one loaded keeps working).

Exit status 0 on success; on failure the compiler output is shown and the status is 1.
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src"
LAYER = ROOT / "f2py" / "impactchain_f2py.f90"
SUPPORT = ROOT / "f2py" / "chain_bridge.f90"
DEST = ROOT / "post"
MODULE = "_kernels"
WRAPPED = ("ic_run", "ic_jacobian", "ic_random_start")

#: What `fpm build --profile release --verbose` passes to gfortran (fpm 0.12.0, gfortran 12),
#: in the same order. Keep in sync with fpm: the bit-identity tests in post/tests/test_api.py
#: fail if they drift apart.
RELEASE_FLAGS = [
    "-O3", "-funroll-loops", "-Wimplicit-interface", "-fPIC", "-fmax-errors=1",
    "-fcoarray=single", "-fimplicit-none", "-Werror=implicit-interface", "-ffree-form",
]
#: Libraries, in link order (fpm links -lhdf5 -lhdf5hl_fortran -lhdf5_fortran -lhdf5_hl
#: -llapack -lblas for an executable; for a shared object the Fortran wrappers go first).
LIBRARIES = ["hdf5hl_fortran", "hdf5_fortran", "hdf5_hl", "hdf5", "lapack", "blas"]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--force", action="store_true", help="rebuild even if up to date")
    parser.add_argument("--keep", action="store_true",
                        help="keep the temporary build directory (its path is printed)")
    parser.add_argument("--quiet", action="store_true", help="only report errors")
    args = parser.parse_args(argv)

    target = DEST / (MODULE + sysconfig.get_config_var("EXT_SUFFIX"))
    inputs = [*sorted(SRC.glob("*.f90")), LAYER, SUPPORT, Path(__file__).resolve()]
    if not args.force and target.exists() and all(
            target.stat().st_mtime >= p.stat().st_mtime for p in inputs):
        if not args.quiet:
            print(f"impactchain: {target.relative_to(ROOT)} is up to date")
        return 0

    start = time.monotonic()
    work = Path(tempfile.mkdtemp(prefix="impactchain-f2py-"))
    try:
        built = build(work)
        tmp = target.with_name(target.name + ".tmp")
        shutil.copy2(built, tmp)
        os.replace(tmp, target)
    except BuildError as exc:
        print(f"impactchain: building the Python extension failed: {exc}", file=sys.stderr)
        if not args.keep:
            print("(rerun with --keep to inspect the build directory)", file=sys.stderr)
        return 1
    finally:
        if args.keep:
            print(f"impactchain: build directory kept: {work}")
        else:
            shutil.rmtree(work, ignore_errors=True)
    if not args.quiet:
        print(f"impactchain: built {target.relative_to(ROOT)} "
              f"in {time.monotonic() - start:.1f} s")
    return 0


class BuildError(RuntimeError):
    """A build step failed; the message holds the command and its output."""


def build(work: Path) -> Path:
    """Run the steps in `work`; return the path of the built extension."""
    env = dict(os.environ)
    # meson and ninja live next to the venv's python
    env["PATH"] = os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")])
    fc = env.get("FC", "gfortran")
    env["FC"] = fc
    hdf5_inc = pkg_config("--cflags-only-I", env)
    hdf5_lib = pkg_config("--libs-only-L", env)

    mods = work / "mod"
    objs = work / "obj"
    mods.mkdir()
    objs.mkdir()
    objects = []
    for source in [*dependency_order(sorted(SRC.glob("*.f90"))), SUPPORT]:
        obj = objs / (source.stem + ".o")
        run([fc, "-c", str(source), *RELEASE_FLAGS, *hdf5_inc, "-J", str(mods),
             f"-I{mods}", "-o", str(obj)], work, env)
        objects.append(obj)

    # f2py compiles the layer with its own flags: check it first with the project's, so
    # that an implicit interface (a missing `use ..., only:`) fails the build
    run([fc, "-fsyntax-only", str(LAYER), *RELEASE_FLAGS, f"-I{mods}"], work, env)
    f2py = [sys.executable, "-m", "numpy.f2py"]
    shutil.copy2(LAYER, work / LAYER.name)
    run([*f2py, "-m", MODULE, LAYER.name, "-h", f"{MODULE}.pyf", "--overwrite-signature",
         "only:", *WRAPPED, ":"], work, env)
    run([*f2py, "-c", "--backend", "meson", f"{MODULE}.pyf", LAYER.name,
         *map(str, objects), f"-I{mods}", *hdf5_lib,
         *[f"-l{lib}" for lib in LIBRARIES]], work, env)
    found = sorted(work.glob(f"{MODULE}*.so")) + sorted(work.glob(f"{MODULE}*.pyd"))
    if not found:
        raise BuildError(f"f2py produced no {MODULE}*.so in {work}")
    return found[0]


def dependency_order(sources: list[Path]) -> list[Path]:
    """Sources sorted so that every module is compiled before the files that use it."""
    defines: dict[str, Path] = {}
    uses: dict[Path, set[str]] = {}
    for path in sources:
        text = path.read_text()
        for name in re.findall(r"^\s*module\s+(\w+)\s*$", text, re.M | re.I):
            defines[name.lower()] = path
        uses[path] = {m.lower() for m in re.findall(
            r"^\s*use\s*(?:,\s*non_intrinsic\s*)?(?:::)?\s*(\w+)", text, re.M | re.I)}
    ordered: list[Path] = []
    state: dict[Path, str] = {}

    def visit(path: Path) -> None:
        if state.get(path) == "done":
            return
        if state.get(path) == "open":
            raise BuildError(f"circular module dependency through {path.name}")
        state[path] = "open"
        for name in sorted(uses[path]):
            if name in defines and defines[name] != path:
                visit(defines[name])
        state[path] = "done"
        ordered.append(path)

    for path in sources:
        visit(path)
    return ordered


def pkg_config(option: str, env: dict[str, str]) -> list[str]:
    """HDF5's flags from pkg-config, as fpm finds them (Debian: hdf5 = hdf5-serial)."""
    try:
        out = subprocess.run(["pkg-config", option, "hdf5"], capture_output=True, text=True,
                             env=env, check=True).stdout
    except (OSError, subprocess.CalledProcessError) as exc:
        raise BuildError(f"pkg-config cannot find HDF5 ({exc}); install libhdf5-dev and "
                         "pkg-config (make setup does)") from exc
    return out.split()


def run(cmd: list[str], cwd: Path, env: dict[str, str]) -> None:
    """Run a build command quietly; on failure raise with the tail of its output."""
    result = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    if result.returncode != 0:
        raise BuildError(f"command failed ({result.returncode}): {' '.join(cmd)}\n"
                         f"{result.stdout[-6000:]}\n{result.stderr[-6000:]}")


if __name__ == "__main__":
    sys.exit(main())
