"""Rooms of one concept: fail on a source file over 600 lines or a procedure over 100 lines.

Checked: the Fortran of src/, app/, mpi/ and f2py/, and the Python package (the folder of
`impactchain/__init__.py` in the repository, outside build/ and .venv/). A procedure is a
Fortran subroutine or function (module procedures, a submodule's `module procedure` bodies and
contained ones; not the declarations of an interface block) or a Python `def`. Its length runs
from its first line to its end, less the procedures it contains, which count on their own.

A file may be larger when its header (the comment lines before its first statement, or a
Python module's docstring) holds one sentence that starts with the marker `Size:` and says why,
e.g. `!> Size: the event loop stays in one file, which gfortran inlines into itself.`; the
sentence excuses the file and its procedures. Without a reason (five words or more, ending in
a full stop) the marker excuses nothing.

    python test/check_sizes.py [ROOT]     # exit 0, or 1 with one line per offender

`make test` runs it (test/python/test_sizes.py), on this tree and on a tree made to fail.
"""

from __future__ import annotations

import ast
import os
import re
import sys
from pathlib import Path

MAX_FILE = 600        #: lines of a source file
MAX_PROCEDURE = 100   #: lines of a procedure, less those it contains
MARKER = "Size:"      #: the start of the header's sentence that excuses a file
MIN_WORDS = 5         #: of that sentence, to say why rather than that
FORTRAN = ("src", "app", "mpi", "f2py")  #: folders whose Fortran is checked
SKIPPED = {"build", ".venv", ".git"}

_SENTENCE = re.compile(re.escape(MARKER) + r"\s*(.*?\.)(?:\s|$)")

_PREFIX = (r"(?:(?:pure|impure|elemental|recursive|non_recursive|module|integer|real|logical"
           r"|complex|character|double\s+precision|(?:type|class)(?=\s*\())"
           r"(?:\s*\((?:[^()]|\([^()]*\))*\))?\s+)*")
_HEADER = re.compile(r"^" + _PREFIX + r"(subroutine|function)\s+(\w+)\b", re.I)
_SEPARATE = re.compile(r"^module\s+procedure\s+(\w+)\s*$", re.I)
_END = re.compile(r"^end(?:\s*(?:subroutine|function|procedure)(?:\s+\w+)?)?\s*$", re.I)
_UNIT = re.compile(r"^(?:(module|submodule\s*\([^)]*\)|program)\s+(\w+)|block\s+data\b)", re.I)
_UNIT_END = re.compile(r"^end\s*(module|submodule|program|block\s*data)\b", re.I)
_INTERFACE = re.compile(r"^(?:abstract\s+)?interface\b", re.I)
_INTERFACE_END = re.compile(r"^end\s*interface\b", re.I)


def _statements(text: str) -> list[tuple[int, str]]:
    """Free-form Fortran as (first line number, statement), comments and continuations joined;
    preprocessor lines left out."""
    out: list[tuple[int, str]] = []
    pending, start = "", 0
    for number, line in enumerate(text.splitlines(), 1):
        if line.lstrip().startswith("#"):
            continue
        code = _strip_comment(line).strip()
        if pending:
            code = code[1:].lstrip() if code.startswith("&") else code
        elif code:
            start = number
        if code.endswith("&"):
            pending += code[:-1] + " "
            continue
        statement = (pending + code).strip()
        pending = ""
        for part in statement.split(";"):
            if part.strip():
                out.append((start, part.strip()))
    return out


def _strip_comment(line: str) -> str:
    """The line up to a `!` outside quotes."""
    quote = None
    for i, c in enumerate(line):
        if quote:
            if c == quote:
                quote = None
        elif c in "'\"":
            quote = c
        elif c == "!":
            return line[:i]
    return line


def fortran_procedures(text: str) -> list[tuple[str, int, int]]:
    """Each procedure as (name, first line, length less contained procedures)."""
    found: list[tuple[str, int, int]] = []
    stack: list[list] = []   # open scopes: [kind, name, first line, contained lines]
    for number, statement in _statements(text):
        if stack and stack[-1][0] == "interface":
            if _INTERFACE_END.match(statement):
                stack.pop()
            continue
        if _INTERFACE.match(statement):
            stack.append(["interface", "", number, 0])
        elif _UNIT_END.match(statement):
            stack.pop()
        elif (end := _END.match(statement)) and stack:
            kind, name, first, inner = stack.pop()
            if kind != "procedure":
                continue
            span = number - first + 1
            found.append((name, first, span - inner))
            if stack and stack[-1][0] == "procedure":
                stack[-1][3] += span
        elif (head := _SEPARATE.match(statement)) or (head := _HEADER.match(statement)):
            stack.append(["procedure", head.group(head.lastindex), number, 0])
        elif _UNIT.match(statement):
            stack.append(["unit", "", number, 0])
    return found


def python_procedures(text: str) -> list[tuple[str, int, int]]:
    """Each `def` as (qualified name, first line, length less nested defs and classes)."""
    found: list[tuple[str, int, int]] = []

    def visit(node: ast.AST, prefix: str) -> int:
        """Walks node's children; returns the lines of the defs and classes among them."""
        inner = 0
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                span = child.end_lineno - child.lineno + 1
                nested = visit(child, f"{prefix}{child.name}.")
                if not isinstance(child, ast.ClassDef):
                    found.append((prefix + child.name, child.lineno, span - nested))
                inner += span
            else:
                inner += visit(child, prefix)
        return inner

    visit(ast.parse(text), "")
    return found


def header(path: Path, text: str) -> str:
    """The file's header: its leading comment lines, or a Python module's docstring."""
    if path.suffix == ".py":
        doc = ast.get_docstring(ast.parse(text), clean=True) or ""
        lines = []
        for line in text.splitlines():
            if not line.startswith("#"):
                break
            lines.append(line.lstrip("#"))
        return " ".join(lines + doc.split())
    lines = []
    for line in text.splitlines():
        stripped = line.strip()
        if stripped and not stripped.startswith("!"):
            break
        lines.append(stripped.lstrip("!>").strip())
    return " ".join(" ".join(lines).split())


def reason(path: Path, text: str) -> str | None:
    """The header's sentence saying why the file may be larger, if any."""
    match = _SENTENCE.search(header(path, text))
    if match is None or len(match.group(1).split()) < MIN_WORDS:
        return None
    return match.group(1)


def sources(root: Path) -> list[Path]:
    """The Fortran of the checked folders and the Python package's modules."""
    def kept(path: Path) -> bool:
        return not SKIPPED & set(path.relative_to(root).parts)

    files = [p for folder in FORTRAN if (root / folder).is_dir()
             for p in sorted((root / folder).rglob("*")) if p.suffix in (".f90", ".F90")]
    for folder, dirs, names in os.walk(root):
        dirs[:] = sorted(d for d in dirs if d not in SKIPPED and not d.startswith("."))
        if Path(folder).name == "impactchain" and "__init__.py" in names:
            files += sorted(Path(folder).rglob("*.py"))
    return [p for p in files if kept(p)]


def check(root: Path) -> tuple[list[str], list[str]]:
    """Every offender under root, one line each, and the files excused by their header."""
    problems, excused = [], []
    for path in sources(root):
        text = path.read_text()
        name = path.relative_to(root)
        procedures = (python_procedures if path.suffix == ".py" else fortran_procedures)(text)
        lines = len(text.splitlines())
        over = [f"{name}: {lines} lines (at most {MAX_FILE})"] if lines > MAX_FILE else []
        over += [f"{name}:{first}: procedure {proc} has {length} lines (at most {MAX_PROCEDURE})"
                 for proc, first, length in procedures if length > MAX_PROCEDURE]
        why = reason(path, text) if over else None
        if why:
            excused.append(f"{name}: {lines} lines, excused: {why}")
        else:
            problems += over
    return problems, excused


def main(argv: list[str]) -> int:
    root = Path(argv[1]) if len(argv) > 1 else Path(__file__).resolve().parents[1]
    problems, excused = check(root)
    for line in excused:
        print("check_sizes: " + line)
    for line in problems:
        print("check_sizes: " + line, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv))
