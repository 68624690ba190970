"""Fortran namelist text: reading the groups and keys of the simulator's input and resolved
namelists (:func:`namelist_groups`), and writing the input of a command-line run equal to a run
made in memory (:func:`equivalent_namelist`).
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np

__all__ = ["namelist_groups", "equivalent_namelist"]


def namelist_groups(text: str) -> dict[str, dict[str, str]]:
    """``{group: {key: value text}}`` of a Fortran namelist text, lower-case names.

    Enough of the namelist syntax for the simulator's input and resolved namelists:
    ``!`` comments, quoted strings, ``key = value`` pairs separated by commas or
    newlines, list values (``x0 = 0.1, 0.2``) kept as their text. A later group of the
    same name adds to the earlier one.
    """
    groups: dict[str, dict[str, str]] = {}
    for name, body in _namelist_bodies(_strip_comments(text)):
        group = groups.setdefault(name, {})
        keys = list(_KEY.finditer(_mask_strings(body)))
        for key, following in zip(keys, [*keys[1:], None]):
            end = following.start() if following is not None else len(body)
            value = body[key.end():end].strip().rstrip(",").strip()
            group[key.group(1).lower()] = value
    return groups


_KEY = re.compile(r"(?:^|(?<=[,\s]))([A-Za-z]\w*)\s*=(?!=)")


def _strip_comments(text: str) -> str:
    lines = []
    for line in text.splitlines():
        quote = ""
        for i, char in enumerate(line):
            if quote:
                if char == quote:
                    quote = ""
            elif char in "'\"":
                quote = char
            elif char == "!":
                line = line[:i]
                break
        lines.append(line)
    return "\n".join(lines)


def _namelist_bodies(text: str) -> Iterable[tuple[str, str]]:
    """(group name, body) of every ``&group ... /`` (a ``/`` inside quotes is text)."""
    i = 0
    while (start := text.find("&", i)) >= 0:
        match = re.match(r"&([A-Za-z]\w*)", text[start:])
        if match is None:
            i = start + 1
            continue
        j, quote = start + match.end(), ""
        while j < len(text):
            char = text[j]
            if quote:
                if char == quote:
                    quote = ""
            elif char in "'\"":
                quote = char
            elif char == "/":
                break
            j += 1
        yield match.group(1).lower(), text[start + match.end():j]
        i = j + 1


def _mask_strings(body: str) -> str:
    """``body`` with the inside of quoted strings replaced by ``#`` (same length), so that
    the key search finds no ``key =`` inside a string value."""
    out, quote = [], ""
    for char in body:
        if quote:
            if char == quote:
                quote = ""
                out.append(char)
            else:
                out.append("#")
        else:
            if char in "'\"":
                quote = char
            out.append(char)
    return "".join(out)


_LISTED_START = 1000
"""The equivalent namelist of an in-memory run lists x0 and v0 up to this many values."""


def equivalent_namelist(config: Mapping[str, Any], lyapunov: bool) -> str:
    """The input namelist of a command-line run equal to this in-memory one."""

    def real(value: Any) -> str:
        return repr(float(value))

    spacing = np.atleast_1d(np.asarray(config["spacing"], dtype=float))
    lines = [
        "! made in memory by impactchain.api; the equivalent command-line input:",
        f"&chain n = {int(config['n'])}, amplitude = {real(config['amplitude'])}, "
        f"omega = {real(config['omega'])}, damping = {real(config['damping'])}, "
        f"restitution = {real(config['restitution'])}, "
        f"spacing = {', '.join(real(a) for a in spacing)}, "
        f"boundary = '{config['boundary']}' /",
    ]
    x0, v0 = config.get("x0"), config.get("v0")
    if x0 is None or v0 is None:
        lines.append("&initial kind = 'rest' /")
    elif len(x0) > _LISTED_START:
        lines.append(f"&initial kind = 'explicit' /  ! x0 and v0: {len(x0)} values each, "
                     "not listed")
    else:
        lines.append(f"&initial kind = 'explicit', x0 = {', '.join(map(real, x0))}, "
                     f"v0 = {', '.join(map(real, v0))} /")
    record = ".true." if config.get("events", False) else ".false."
    lines.append(f"&run transient = {int(config['transient'])}, cycles = "
                 f"{int(config['cycles'])}, phase = {real(config['phase'])}, "
                 f"stick_speed = {real(config['stick_speed'])}, record_events = {record} /")
    if lyapunov:
        window = int(config.get("window", 0))
        lines.append(f"&lyapunov enabled = .true., vectors = {int(config.get('vectors', 0))}, "
                     f"qr_every = {int(config.get('qr_every', 1))}"
                     + (f", window = {window}" if window else "") + " /")
    if "jacobian_cycles" in config:  # a Floquet run: the Jacobian only, no exponents
        lines.append("&lyapunov enabled = .false., jacobian = .true., jacobian_cycles = "
                     f"{int(config['jacobian_cycles'])} /")
    overrides = config.get("overrides", ())
    if overrides:  # the other keys given, which the command line takes as they are
        lines.append("! with: " + " ".join(f"--set {line}" for line in overrides))
    return "\n".join(lines) + "\n"
