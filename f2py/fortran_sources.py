"""Print the Fortran and C sources under a directory, one a line: what meson.build compiles.

Usage: ``python f2py/fortran_sources.py DIR`` (meson.build gives the absolute path of src/).

Every ``.f90`` / ``.F90`` / ``.c`` file under DIR, subdirectories included (fpm's own rule for
``src/``), sorted, as POSIX paths relative to DIR. meson.build runs this when the build is
configured, so that no list of sources is kept by hand: a file added, renamed or removed in
``src/`` is picked up by the next configuration (``pip install .`` configures again every
time). Meson orders modules and submodules itself.
"""

from __future__ import annotations

import sys
from pathlib import Path


def fortran_sources(folder: Path) -> list[str]:
    """The relative paths of the Fortran (and C) sources under ``folder``, sorted."""
    found = [p for p in folder.rglob("*") if p.is_file() and p.suffix in (".f90", ".F90", ".c")]
    if not found:
        raise SystemExit(f"fortran_sources: no .f90 file under {folder}")
    return sorted(p.relative_to(folder).as_posix() for p in found)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        raise SystemExit("usage: python f2py/fortran_sources.py DIR")
    print("\n".join(fortran_sources(Path(sys.argv[1]))))
