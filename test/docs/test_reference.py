"""The input and output references of the site, generated from ``impactchain --schema``
(docs/hooks/reference.py), on a sample of the agreed JSON (data/schema_sample.json)."""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SAMPLE = Path(__file__).parent / "data" / "schema_sample.json"


def _hook():
    spec = importlib.util.spec_from_file_location("reference_hook",
                                                  ROOT / "docs" / "hooks" / "reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


reference = _hook()


@pytest.fixture
def schema() -> dict:
    return json.loads(SAMPLE.read_text())


def _table_rows(page: str, heading: str) -> list[list[str]]:
    """The cells of the table under ``heading``, header row and rule left out."""
    lines = page.splitlines()
    at = lines.index(heading) + 4
    rows = []
    while at < len(lines) and lines[at].startswith("|"):
        rows.append([c.strip() for c in lines[at].strip("|").split(" | ")])
        at += 1
    return rows


def test_every_key_is_a_row_of_its_group_in_the_schemas_order(schema: dict) -> None:
    page = reference.inputs_markdown(schema)
    headings = [l for l in page.splitlines() if l.startswith("## ")]
    assert headings == ["## `&chain`", "## `&run`", "## `&lyapunov`"]
    chain = _table_rows(page, "## `&chain`")
    assert [r[0] for r in chain] == ["`n`", "`spacing`", "`boundary`"]
    n, spacing, boundary = chain
    assert n[1:5] == ["integer", "required", "1 .. 10^7", "`1`"]
    assert spacing[1:3] == ["real, list", "`n + 1 values of 1`"]
    assert spacing[5] == "a: one value, or n+1 values \\| bond 0 first"   # the bar escaped
    assert boundary[3] == "`fixed`, `free`"
    assert _table_rows(page, "## `&lyapunov`")[0][2] == "`cycles/10`"
    assert all(len(r) == 6 for r in chain)


def test_every_dataset_is_a_row_of_its_kind_of_file(schema: dict) -> None:
    page = reference.outputs_markdown(schema)
    run = _table_rows(page, "## Files of a single run")
    assert [r[0] for r in run] == ["`/strobe/x`", "`/lyapunov/exponents`", "`/@complete`"]
    assert run[0][2] == "record, oscillator" and run[2][2] == "scalar"
    assert run[1][4] == "`bits/cycle` (model: `1/time`)" and run[1][5] == "lyapunov enabled"
    assert [r[0] for r in _table_rows(page, "## Files of a sweep (`&sweep`)")] == ["`/sweep/point`"]
    assert _table_rows(page, "## Files of a census (`&census`)")[0][6] == \
        "basin fraction of each attractor"


@pytest.mark.parametrize("change, words", [
    (lambda s: s.update(schema_version=2), "schema_version 2"),
    (lambda s: s.pop("outputs"), "no 'outputs' table"),
    (lambda s: s.update(inputs=[]), "no 'inputs' table"),
])
def test_a_schema_of_another_shape_is_refused(schema: dict, change, words: str) -> None:
    change(schema)
    with pytest.raises(reference.SchemaUnavailable, match=words):
        reference.checked(schema)


def test_a_program_without_schema_stops_the_build_saying_so() -> None:
    no_option = [sys.executable, "-c",
                 "import sys; print(\"impactchain: error: unknown option '--schema'\", "
                 "file=sys.stderr); sys.exit(2)"]
    with pytest.raises(reference.SchemaUnavailable,
                       match=r"exited with status 2: impactchain: error: unknown option "
                             r"'--schema'\. The input and output references are generated "
                             r"from the program's --schema"):
        reference.read_schema(no_option)
    with pytest.raises(reference.SchemaUnavailable, match="printed no JSON"):
        reference.read_schema([sys.executable, "-c", "print('usage: impactchain ...')"])


def test_the_programs_json_is_read(schema: dict) -> None:
    printer = [sys.executable, "-c", f"print(open({str(SAMPLE)!r}).read())"]
    assert reference.read_schema(printer) == schema
