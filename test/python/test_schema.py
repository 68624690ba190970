"""`impactchain --schema`: the input schema (src/runs/chain_inputs.f90) as JSON, the one home
of every key. It is valid JSON, it lists exactly the keys the reader accepts (the reader's own
message for an unknown key names them), and each default it states is what a run without the
key uses (the resolved namelist of --check)."""
from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import h5py
import numpy as np
import pytest

from simulator import impactchain_exe  # noqa: F401 (fixture)

BASE = """&chain n = 4, amplitude = 1.7, omega = 1.5 /
&initial /
&run /
&lyapunov /
&output file = 'out.h5' /
"""
#: An input with each optional group of the table (sweep, continuation and census exclude
#: each other): the keys of every group are resolved in one of them.
INPUTS = {
    "base": BASE,
    "sweep": BASE + "&sweep parameter = 'amplitude', start = 1.0, stop = 2.0, step = 0.5 /\n",
    "continuation": BASE + "&continuation parameter = 'amplitude', stop = 2.0, step = 0.1 /\n",
    "census": BASE + "&census /\n",
}
OPTIONAL = {"sweep", "continuation", "census"}


@pytest.fixture(scope="module")
def schema(impactchain_exe):  # noqa: F811
    out = subprocess.run([str(impactchain_exe), "--schema"], capture_output=True, text=True,
                         timeout=60)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def check(exe: Path, text: str, tmp_path: Path) -> subprocess.CompletedProcess:
    (tmp_path / "in.nml").write_text(text)
    return subprocess.run([str(exe), "--check", "in.nml"], cwd=tmp_path, capture_output=True,
                          text=True, timeout=60)


def resolved(stdout: str) -> dict[str, dict[str, str]]:
    """{group: {key: value text}} of a resolved namelist (one group a line)."""
    groups = {}
    for line in stdout.splitlines():
        match = re.match(r"&(\w+)\s*(.*?)\s*/\s*$", line)
        assert match, line
        items = re.findall(r"(\w+) = ((?:'[^']*'|[^,'])+(?:, [-+0-9.eE]+)*)(?:, |$)",
                           match.group(2))
        groups[match.group(1)] = {key: value.strip() for key, value in items}
    return groups


def as_json_value(text: str, kind: str):
    if kind == "string":
        return text.strip("'")
    if kind == "logical":
        return text.lower().strip(".").startswith("t")
    if kind == "integer":
        return int(text)
    return float(text)


def namelist_value(key: dict) -> str:
    value = key["default"]
    if key["type"] == "string":
        return f"'{value}'"
    if key["type"] == "logical":
        return ".true." if value else ".false."
    return repr(value)


def test_schema_is_the_agreed_json(schema):
    assert schema["schema_version"] == 1
    assert isinstance(schema["outputs"], list)
    fields = {"group", "name", "type", "list", "required", "default", "default_text", "range",
              "min", "max", "choices", "units", "help"}
    for key in schema["inputs"]:
        assert set(key) == fields, key
        assert key["type"] in ("integer", "real", "logical", "string")
        assert key["help"] and key["default_text"], key
        if key["required"]:
            assert key["default"] is None, key
        if key["choices"] is not None and key["default"] is not None:
            assert key["default"] in key["choices"], key
        for bound in ("min", "max"):
            if key[bound] is not None and key["default"] is not None and not key["list"]:
                assert (key["default"] >= key[bound]) if bound == "min" else \
                    (key["default"] <= key[bound]), key
    names = [(k["group"], k["name"]) for k in schema["inputs"]]
    assert len(names) == len(set(names))


def test_schema_lists_exactly_the_keys_the_reader_accepts(schema, impactchain_exe, tmp_path):
    """Group by group, the reader's list of valid keys (in the message refusing an unknown
    one) is the schema's; and each key of the schema is read, not refused as unknown."""
    groups: dict[str, list[str]] = {}
    for key in schema["inputs"]:
        groups.setdefault(key["group"], []).append(key["name"])
    assert list(groups) == ["chain", "initial", "run", "lyapunov", "output", "sweep",
                            "continuation", "census"]
    for group, names in groups.items():
        text = BASE.replace(f"&{group} ", f"&{group} zz_not_a_key = 1, ") \
            if f"&{group} " in BASE else BASE + f"&{group} zz_not_a_key = 1 /\n"
        out = check(impactchain_exe, text, tmp_path)
        match = re.search(rf"The keys of &{group} are ([\w, ]+)", out.stderr)
        assert match, out.stderr
        assert match.group(1).split(", ") == names
    for key in schema["inputs"]:
        value = namelist_value(key) if key["default"] is not None else \
            {"real": "1.0", "integer": "1", "string": "'x1'", "logical": ".true."}[key["type"]]
        line = f"&{key['group']} {key['name']} = {value} /\n"
        text = BASE.replace(f"&{key['group']} ", f"&{key['group']} {key['name']} = {value}, ") \
            if f"&{key['group']} " in BASE else BASE + line
        out = check(impactchain_exe, text, tmp_path)
        assert "unknown key" not in out.stderr, (key, out.stderr)


@pytest.mark.parametrize("name", INPUTS)
def test_defaults_are_what_a_run_without_the_key_uses(schema, impactchain_exe, tmp_path, name):
    """Every key with a default: its value in the resolved input when left out is the
    default, and giving it the default changes nothing in the resolved input."""
    text = INPUTS[name]
    out = check(impactchain_exe, text, tmp_path)
    assert out.returncode == 0, out.stderr
    used = resolved(out.stdout)
    groups = {"chain", "initial", "run", "lyapunov", "output"} | ({name} & OPTIONAL)
    compared = 0
    for key in schema["inputs"]:
        if key["group"] not in groups or key["default"] is None:
            continue
        if key["name"] in used[key["group"]]:
            assert as_json_value(used[key["group"]][key["name"]], key["type"]) == \
                key["default"], key
            compared += 1
        given = text.replace(f"&{key['group']} ",
                             f"&{key['group']} {key['name']} = {namelist_value(key)}, ", 1)
        again = check(impactchain_exe, given, tmp_path)
        assert again.returncode == 0, (key, again.stderr)
        strip = re.compile(rf"(, )?\b{key['name']} = [^,/]*?(?=,| /)")
        assert strip.sub("", again.stdout) == strip.sub("", out.stdout), key
    assert compared >= 5


def test_defaults_are_what_a_run_without_the_key_uses_bit_for_bit(schema, impactchain_exe,
                                                                  tmp_path):
    """A single run (with exponents) without a key and with the key at its stated default
    writes the same file, value for value (the reader's copy into the run uses the table's
    default, whatever the echo says)."""
    base = BASE.replace("&run /", "&run transient = 3, cycles = 6 /").replace(
        "&initial /", "&initial kind = 'random', x_amp = 0.2, v_amp = 0.1 /")
    skipped = {("output", "file"), ("output", "overwrite"), ("lyapunov", "covariant"),
               ("lyapunov", "window")}

    def contents(text: str) -> dict[str, bytes]:
        (tmp_path / "out.h5").unlink(missing_ok=True)
        (tmp_path / "in.nml").write_text(text)
        out = subprocess.run([str(impactchain_exe), "--quiet", "in.nml"], cwd=tmp_path,
                             capture_output=True, text=True, timeout=60)
        assert out.returncode == 0, (text, out.stderr)
        items = {}
        with h5py.File(tmp_path / "out.h5") as f:
            def visit(name, obj):
                if isinstance(obj, h5py.Dataset):
                    items[name] = np.asarray(obj[()]).tobytes()
                for attr in obj.attrs:
                    value = np.asarray(obj.attrs[attr])
                    # (the echoed input differs by the key; references are addresses)
                    if attr not in ("input_namelist", "resolved_namelist", "DIMENSION_LIST",
                                    "REFERENCE_LIST") and value.dtype != object:
                        items[f"{name}@{attr}"] = value.tobytes()
            f.visititems(visit)
            visit("/", f)
        return items

    reference = contents(base)
    compared = 0
    for key in schema["inputs"]:
        if key["group"] not in ("chain", "initial", "run", "lyapunov", "output") or \
                key["default"] is None or (key["group"], key["name"]) in skipped:
            continue
        if re.search(rf"&{key['group']} [^/]*\b{key['name']} =", base):
            continue
        given = base.replace(f"&{key['group']} ",
                             f"&{key['group']} {key['name']} = {namelist_value(key)}, ", 1)
        assert contents(given) == reference, key
        compared += 1
    assert compared >= 15


def test_python_reads_the_same_table_and_takes_its_defaults(schema):
    """impactchain.schema.inputs() is --schema's "inputs" (read from the extension, never
    re-typed), and the API's keyword defaults are the table's (help() shows them)."""
    import inspect

    from impactchain import api
    from impactchain import schema as py_schema

    assert py_schema.inputs() == schema["inputs"]
    table = {(k["group"], k["name"]): k["default"] for k in schema["inputs"]}
    signature = inspect.signature(api.simulate)
    # the keys a call leaves out take the table's defaults: the run's record says so
    used = api.simulate(2, 0.5, 1.5, cycles=1).params
    for name, group in [("damping", "chain"), ("restitution", "chain"), ("boundary", "chain"),
                        ("transient", "run"), ("phase", "run"), ("stick_speed", "run")]:
        assert used[name] == table[(group, name)], name
    assert set(used["spacing"]) == {table[("chain", "spacing")]}
    assert signature.parameters["events"].default == table[("run", "record_events")]
    assert inspect.signature(api.floquet).parameters["period"].default == \
        table[("lyapunov", "jacobian_cycles")]
    continuation = inspect.signature(api.continuation).parameters
    for name in ("period", "max_points", "doublings"):
        assert continuation[name].default == table[("continuation", name)], name
    assert inspect.signature(api.sweep).parameters["mode"].default == table[("sweep", "mode")]
    random = inspect.signature(api.random_start).parameters
    for name in ("seed", "x_amp", "v_amp"):
        assert random[name].default == table[("initial", name)], name
    assert "damping" not in signature.parameters  # one of **keys, not a repeated argument


def test_a_parameter_has_one_unit_in_the_input_and_the_files(schema):
    """The unit of a key (input reference) is the unit its /params entry states in every
    file (model_units; none for a pure number): the damping ratio b a pure number, A a
    length, w a frequency."""
    inputs = {(k["group"], k["name"]): k["units"] for k in schema["inputs"]}
    params = {e["path"].split("/")[-1].lstrip("@"): e for e in schema["outputs"]
              if e["path"].startswith("/params/") and e["file"] == "run"}
    shared = [(g, n) for (g, n) in inputs if n in params and g in ("chain", "run")]
    assert {n for _, n in shared} >= {"damping", "restitution", "amplitude", "omega",
                                      "spacing", "transient", "cycles"}
    for group, name in shared:
        stated = params[name]["model_units"] or params[name]["units"]
        assert stated == inputs[group, name], (group, name, stated, inputs[group, name])
    assert inputs["chain", "damping"] == "1" and inputs["chain", "amplitude"] == "length"
