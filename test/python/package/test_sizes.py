"""Rooms of one concept (issue 31, item 8): no module of the package over 600 lines and no
function over 100, so that each file holds one topic a reader can take in whole.

``impactchain.api`` is exempt while it is rewritten around the input schema (issue 31, item 2).
"""

from __future__ import annotations

import ast
from pathlib import Path

SOURCE = Path(__file__).resolve().parents[3] / "python" / "impactchain"
MAX_MODULE_LINES = 600
MAX_FUNCTION_LINES = 100
EXEMPT = {"api.py"}


def oversized(root: Path) -> list[str]:
    """Every module of ``root`` over MAX_MODULE_LINES and every function over
    MAX_FUNCTION_LINES (decorators included), as ``path: what``."""
    found = []
    for path in sorted(root.rglob("*.py")):
        name = str(path.relative_to(root))
        if name in EXEMPT:
            continue
        text = path.read_text()
        if text.count("\n") > MAX_MODULE_LINES:
            found.append(f"{name}: {text.count(chr(10))} lines")
        for node in ast.walk(ast.parse(text)):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                start = min([node.lineno] + [d.lineno for d in node.decorator_list])
                length = node.end_lineno - start + 1 if node.end_lineno else 0
                if length > MAX_FUNCTION_LINES:
                    found.append(f"{name}:{start}: {node.name}, {length} lines")
    return found


def test_every_module_and_function_of_the_package_is_short() -> None:
    assert not oversized(SOURCE)


def test_a_long_module_and_a_long_function_are_found(tmp_path: Path) -> None:
    body = "".join(f"    x{i} = {i}\n" for i in range(MAX_FUNCTION_LINES))
    (tmp_path / "long_function.py").write_text(f"def f():\n{body}")
    (tmp_path / "long_module.py").write_text("x = 1\n" * (MAX_MODULE_LINES + 1))
    (tmp_path / "api.py").write_text("x = 1\n" * (MAX_MODULE_LINES + 1))
    assert oversized(tmp_path) == ["long_function.py:1: f, 101 lines", "long_module.py: 601 lines"]
