"""The input and output references of the site, generated from ``impactchain --schema``.

The program's own tables (docs/README.md) are the one home of every namelist key and every
dataset a file may hold: this turns their JSON (``schema_version`` 1) into the Markdown pages
``reference/inputs.md`` and ``reference/outputs.md`` each time the site is built, so that
no key or dataset is written by hand. A program without ``--schema`` stops the build.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

SCHEMA_VERSION = 1
FILE_KINDS = {"run": "a single run", "sweep": "a sweep (`&sweep`)",
              "continuation": "a continuation (`&continuation`)", "census": "a census (`&census`)"}


class SchemaUnavailable(RuntimeError):
    """The program could not give its schema: the build stops with this message."""


def read_schema(command: Sequence[str]) -> dict[str, Any]:
    """Run ``command`` (the program and ``--schema``) and return its JSON, checked."""
    try:
        done = subprocess.run(list(command), capture_output=True, text=True, timeout=120)
    except OSError as exc:
        raise SchemaUnavailable(f"cannot run '{' '.join(command)}': {exc}") from exc
    if done.returncode != 0:
        said = (done.stderr.strip() or done.stdout.strip()).splitlines()
        raise SchemaUnavailable(
            f"'{' '.join(command)}' exited with status {done.returncode}"
            f"{': ' + said[0] if said else ''}. The input and output references are generated "
            "from the program's --schema table: build a program that has it (make build)")
    try:
        schema = json.loads(done.stdout)
    except json.JSONDecodeError as exc:
        raise SchemaUnavailable(f"'{' '.join(command)}' printed no JSON: {exc}") from exc
    return checked(schema)


def checked(schema: Any) -> dict[str, Any]:
    """``schema`` if it is the agreed object, else SchemaUnavailable naming what is wrong."""
    if not isinstance(schema, dict):
        raise SchemaUnavailable("the schema is not a JSON object")
    if schema.get("schema_version") != SCHEMA_VERSION:
        raise SchemaUnavailable(f"schema_version {schema.get('schema_version')!r}: these "
                                f"pages are written for version {SCHEMA_VERSION}")
    for table in ("inputs", "outputs"):
        if not isinstance(schema.get(table), list) or not schema[table]:
            raise SchemaUnavailable(f"the schema has no '{table}' table")
    return schema


def _cell(value: Any) -> str:
    """One table cell: Markdown's bars and line breaks kept out."""
    return " ".join(str(value).split()).replace("|", "\\|")


def _code(value: Any) -> str:
    return f"`{_cell(value)}`" if value not in (None, "") else ""


def _in_order(rows: Iterable[Mapping[str, Any]], key: str) -> dict[str, list[Mapping[str, Any]]]:
    """Rows by ``row[key]``, groups and rows in the order the table gives them."""
    grouped: dict[str, list[Mapping[str, Any]]] = {}
    for row in rows:
        grouped.setdefault(row[key], []).append(row)
    return grouped


def _input_type(row: Mapping[str, Any]) -> str:
    return f"{row['type']}, list" if row.get("list") else str(row["type"])


def _input_default(row: Mapping[str, Any]) -> str:
    if row.get("required"):
        return "required"
    return _code(row.get("default_text") or json.dumps(row.get("default")))


def _input_allowed(row: Mapping[str, Any]) -> str:
    if row.get("choices"):
        return ", ".join(_code(c) for c in row["choices"])
    return _cell(row.get("range") or "")


def inputs_markdown(schema: Mapping[str, Any]) -> str:
    """The page of every namelist key: a table per group."""
    lines = ["# Input reference", "",
             "Every key of the input namelist, group by group, as the program checks it "
             "(generated from `impactchain --schema` when the site is built). How to run "
             "an input: [Running](../running.md).", ""]
    for group, rows in _in_order(schema["inputs"], "group").items():
        lines += [f"## `&{group}`", "", "| key | type | default | allowed | units | meaning |",
                  "|---|---|---|---|---|---|"]
        lines += [f"| `{_cell(r['name'])}` | {_input_type(r)} | {_input_default(r)} | "
                  f"{_input_allowed(r)} | {_code(r.get('units'))} | {_cell(r.get('help', ''))} |"
                  for r in rows]
        lines.append("")
    return "\n".join(lines)


def _units(row: Mapping[str, Any]) -> str:
    units = _code(row.get("units"))
    if row.get("model_units"):
        units += f" (model: {_code(row['model_units'])})"
    return units


def outputs_markdown(schema: Mapping[str, Any]) -> str:
    """The page of every dataset and attribute: a table per kind of file."""
    lines = ["# Output reference", "",
             "Every dataset and attribute an output file may hold, by kind of file "
             "(generated from `impactchain --schema` when the site is built). Dimensions "
             "are the netCDF dimension names; how to read a file: [Output](../output.md).",
             ""]
    for kind, rows in _in_order(schema["outputs"], "file").items():
        lines += [f"## Files of {FILE_KINDS.get(kind, f'kind `{_cell(kind)}`')}", "",
                  "| path | kind | dims | type | units | when | meaning |",
                  "|---|---|---|---|---|---|---|"]
        lines += [f"| `{_cell(r['path'])}` | {_cell(r['kind'])} | "
                  f"{_cell(', '.join(r.get('dims') or [])) or 'scalar'} | {_cell(r['dtype'])} | "
                  f"{_units(r)} | {_cell(r.get('when', ''))} | {_cell(r.get('long_name', ''))} |"
                  for r in rows]
        lines.append("")
    return "\n".join(lines)


def program_command() -> list[str]:
    """``impactchain --schema``, the program found on PATH (the Makefile puts .venv/bin first)."""
    program = shutil.which("impactchain")
    if program is None:
        raise SchemaUnavailable("no program 'impactchain' on PATH (make build installs it "
                                "into .venv/bin)")
    return [program, "--schema"]


def on_files(files: Any, config: Any) -> Any:
    """MkDocs hook: add the two generated pages."""
    from mkdocs.exceptions import PluginError
    from mkdocs.structure.files import File

    try:
        saved = os.environ.get("IMPACTCHAIN_SCHEMA_JSON")
        if saved:  # a schema saved earlier (`impactchain --schema > FILE`), e.g. on another machine
            with open(saved, encoding="utf-8") as f:
                schema = checked(json.load(f))
        else:
            schema = read_schema(program_command())
    except (SchemaUnavailable, OSError, json.JSONDecodeError) as exc:
        raise PluginError(f"impactchain docs: the input and output references: {exc}") from exc
    files.append(File.generated(config, "reference/inputs.md", content=inputs_markdown(schema)))
    files.append(File.generated(config, "reference/outputs.md", content=outputs_markdown(schema)))
    return files
