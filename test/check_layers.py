"""The layers of src/ point one way: fail on any `use` of a module from a layer above.

Each folder of src/ is a layer; its README.md names on its `Uses:` line the layers its
modules may use besides their own (src/README.md). The programs outside src/ use the
library through its facades (src/api/); the benchmark also times base's kernels itself.

    python test/check_layers.py [ROOT]     # exit 0, or 1 with one line per problem

The tests mirror the layers (test/README.md): a folder of test/ holding test sources (Fortran
sources, or Python's test_*.py) is a test area named like the folder of src/ it tests, or one
of the test trees of TEST_ROOTS; any other is a problem too.

`make test` runs it (test/python/test_layers.py), on this tree and on trees made to fail.
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

#: folders outside src/ and the layers of src/ they may use
OUTSIDE = {"app": ["api"], "mpi/app": ["api"], "f2py": ["api"], "bench": ["api", "base"]}

#: folders of test/ that hold tests of no one layer, and what they test
TEST_ROOTS = {"test": "the tree's own checks (check_layers.py, check_sizes.py)",
              "test/support/src": "the Fortran suites' shared helpers, a package of their "
                                  "own (test/support/fpm.toml) that every test area uses",
              "test/python": "the simulator's tests, through its command line",
              "test/python/package": "the Python package impactchain (python/impactchain)",
              "test/docs": "the documentation site"}

_USE = re.compile(r"^\s*use\s*(?:,\s*(?:non_)?intrinsic\s*::\s*|::\s*)?(\w+)", re.I | re.M)
_MODULE = re.compile(r"^\s*(?:module\s+(?!procedure\b|function\b|subroutine\b)(\w+)"
                     r"|submodule\s*\(\s*(\w+)\s*\)\s*(\w+))", re.I | re.M)


def _allowed(root: Path) -> dict[str, list[str]]:
    """Each layer of src/ and the layers its README's `Uses:` line names."""
    layers = {}
    for readme in sorted((root / "src").glob("*/README.md")):
        line = next((l for l in readme.read_text().splitlines() if l.startswith("Uses:")), None)
        if line is None:
            raise SystemExit(f"check_layers: {readme.relative_to(root)} has no 'Uses:' line")
        named = re.findall(r"[a-z_]+", line[len("Uses:"):].split("(")[0])
        layers[readme.parent.name] = named
    return layers


def check(root: Path) -> list[str]:
    """Every back-edge under root, one line each (empty: none)."""
    allowed = _allowed(root)
    problems = [f"{path.relative_to(root)}: a source outside every layer (each sits in a "
                f"folder of src/ whose README.md has a 'Uses:' line)"
                for path in sorted((root / "src").rglob("*"))
                if path.suffix in (".f90", ".F90", ".c")
                and path.relative_to(root / "src").parts[0] not in allowed]
    home: dict[str, str] = {}          # module -> its layer
    sources: list[tuple[Path, str]] = []
    for layer in allowed:
        for path in sorted((root / "src" / layer).rglob("*.[fF]90")):
            text = path.read_text()
            for m in _MODULE.finditer(text):
                home[(m.group(1) or m.group(3)).lower()] = layer
            sources.append((path, layer))
    for folder, may in OUTSIDE.items():
        for path in sorted((root / folder).glob("*.[fF]90")) if (root / folder).is_dir() else []:
            sources.append((path, folder))
            allowed[folder] = may
    for path, layer in sources:
        text = path.read_text()
        uses = {m.group(1).lower() for m in _USE.finditer(text)}
        uses |= {m.group(2).lower() for m in _MODULE.finditer(text) if m.group(2)}
        for module in sorted(uses):
            used = home.get(module)
            if used is None or used == layer or used in allowed[layer]:
                continue
            problems.append(f"{path.relative_to(root)}: uses {module} (layer {used}), "
                            f"which layer {layer} may not use (it may use: "
                            f"{', '.join(allowed[layer]) or 'nothing'})")
    return problems


def test_areas(root: Path) -> list[str]:
    """Every folder of test/ holding test sources that is neither a test root nor named
    like a folder of src/, one line each (empty: none)."""
    layers = {readme.parent.name for readme in (root / "src").glob("*/README.md")}
    folders = {path.parent for pattern in ("*.[fF]90", "test_*.py")
               for path in (root / "test").rglob(pattern)}
    return [f"{folder.relative_to(root)}: a test area with no folder src/{folder.name} (an "
            f"area is named like the layer it tests: {', '.join(sorted(layers))})"
            for folder in sorted(folders)
            if folder.relative_to(root).as_posix() not in TEST_ROOTS
            and folder.name not in layers]


def main(argv: list[str]) -> int:
    root = Path(argv[1]) if len(argv) > 1 else Path(__file__).resolve().parents[1]
    problems = check(root) + test_areas(root)
    for line in problems:
        print("check_layers: " + line, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
