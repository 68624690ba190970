"""The input schema: every namelist key with its group, type, default, allowed range, units
and help, as the compiled extension states it (``impactchain --schema``'s ``"inputs"``; the
one home is the Fortran table, src/runs/chain_inputs.f90). :func:`inputs` returns it;
:func:`default` gives one key's default, which the functions of :mod:`impactchain.api` use.
"""

from __future__ import annotations

import functools
import inspect
import json
from collections.abc import Callable
from typing import Any

import numpy as np

__all__ = ["inputs", "default", "key", "with_schema_defaults", "SCHEMA_DEFAULT"]


@functools.lru_cache(maxsize=1)
def _inputs() -> tuple[dict[str, Any], ...]:
    from impactchain import _kernels

    text_len, text = _kernels.ic_input_schema()
    if text_len < 0:
        raise RuntimeError(f"the input schema needs {-text_len} bytes, more than the "
                           "extension's buffer")
    return tuple(json.loads(bytes(np.asarray(text[:text_len]).astype(np.uint8)).decode()))


def inputs() -> list[dict[str, Any]]:
    """Every input key, in group order then table order: dicts with ``group``, ``name``,
    ``type``, ``list``, ``required``, ``default`` (``None`` when required or when it depends
    on other keys), ``default_text``, ``range``, ``min``, ``max``, ``choices``, ``units`` and
    ``help`` (the ``"inputs"`` of ``impactchain --schema``)."""
    return [dict(k) for k in _inputs()]


def key(group: str, name: str) -> dict[str, Any]:
    """The schema of ``&group name``."""
    for k in _inputs():
        if k["group"] == group and k["name"] == name:
            return dict(k)
    raise KeyError(f"&{group}: no key {name!r} in the input schema")


def default(group: str, name: str) -> Any:
    """The default of ``&group name`` as the reader uses it (``None``: required, or it
    depends on other keys)."""
    return key(group, name)["default"]


class _SchemaDefault:
    """The default of a function parameter that the input schema gives (see
    :func:`with_schema_defaults`); shown as such where the extension is not built."""

    def __repr__(self) -> str:
        return "<the input schema's default>"


SCHEMA_DEFAULT: Any = _SchemaDefault()

#: Groups searched, in order, for the key a parameter names
_GROUPS = ("chain", "initial", "run", "lyapunov", "output", "continuation", "sweep", "census")
#: Parameters named otherwise than their key
_ALIASES = {"events": ("run", "record_events")}


def _key_of(name: str) -> tuple[str, str]:
    if name in _ALIASES:
        return _ALIASES[name]
    for group in _GROUPS:
        if any(k["group"] == group and k["name"] == name for k in _inputs()):
            return group, name
    raise KeyError(f"no input key for the parameter {name!r}")


def with_schema_defaults(func: Callable[..., Any] | None = None, /,
                         **keys: tuple[str, str]) -> Any:
    """``func`` whose parameters defaulting to :data:`SCHEMA_DEFAULT` take the default of
    an input key: the one ``keys`` names for the parameter (``period=("lyapunov",
    "jacobian_cycles")``), else the key of the same name, first in &chain, &initial, &run,
    &lyapunov, &output, &continuation, &sweep, &census. Its signature (and so ``help()``)
    shows them, and a call without them passes them. Without the extension the signature
    keeps the marker and a call reads the schema (and so says the extension is missing)."""
    if func is None:
        return functools.partial(with_schema_defaults, **keys)
    signature = inspect.signature(func)
    marked = [p.name for p in signature.parameters.values() if p.default is SCHEMA_DEFAULT]

    def resolved() -> inspect.Signature:
        return signature.replace(parameters=[
            p.replace(default=default(*(keys[p.name] if p.name in keys else _key_of(p.name))))
            if p.name in marked else p for p in signature.parameters.values()])

    @functools.wraps(func)
    def call(*args: Any, **kwargs: Any) -> Any:
        bound = resolved().bind(*args, **kwargs)
        bound.apply_defaults()
        return func(*bound.args, **bound.kwargs)

    try:
        call.__signature__ = resolved()  # type: ignore[attr-defined]
    except ImportError:
        call.__signature__ = signature  # type: ignore[attr-defined]
    return call
