"""The results of :mod:`impactchain.api` as the xarray trees of the files the command line
writes (their ``to_xarray()``): each value at its file path, with the dimensions, units,
``model_units`` and ``long_name`` the file schema gives it (:func:`impactchain.schema.variable`);
xarray makes the coordinates, groups and tree."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from impactchain import schema


def tree(values: Mapping[str, Any], attrs: Mapping[str, Any]) -> Any:
    """An :class:`xarray.DataTree` of ``values`` by file path (``/strobe/x``; ``/stats/@impacts``
    an attribute of its group), with the root's attributes ``attrs``."""
    try:
        import xarray as xr
    except ImportError:
        raise ImportError("to_xarray() needs xarray: pip install xarray") from None
    variables: dict[str, dict[str, Any]] = {}
    group_attrs: dict[str, dict[str, Any]] = {}
    for path, value in values.items():
        group, name = path.rsplit("/", 1)
        if name.startswith("@"):
            group_attrs.setdefault(group, {})[name[1:]] = value
        else:
            variables.setdefault(group, {})[name] = schema.variable(path, value)
    groups = {group: xr.Dataset(variables.get(group, {}), attrs=group_attrs.get(group, {}))
              for group in {*variables, *group_attrs}}
    return xr.DataTree.from_dict({"/": xr.Dataset(attrs=dict(attrs)), **groups})
