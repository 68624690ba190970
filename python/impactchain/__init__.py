"""impactchain from Python: the simulator's kernels, its HDF5 output, analysis and figures.

Modules: :mod:`impactchain.api` (the Fortran kernels on numpy arrays, through the compiled
extension ``impactchain._kernels``), :mod:`impactchain.io` (reading the files),
:mod:`impactchain.results` (what a run holds: the dataclasses :mod:`impactchain.io` returns),
:mod:`impactchain.inmemory` (the same dataclasses from :mod:`impactchain.api` results),
:mod:`impactchain.namelist` (namelist text, read and written), :mod:`impactchain.schema`
(the input keys and every dataset of the files, from the Fortran tables),
:mod:`impactchain.shockwave` (shock-wave construction), :mod:`impactchain.analysis` (period labels, panels),
:mod:`impactchain.figures` (figure functions returning ``matplotlib.figure.Figure``, a module
per topic), :mod:`impactchain.testing` (the invariants the test suites assert) and
:mod:`impactchain.cli` (``python -m impactchain``).
"""

__version__ = "0.1.0"

_SUBMODULES = ("analysis", "api", "cli", "figures", "inmemory", "io", "namelist", "results",
               "schema", "shockwave", "testing")


def __getattr__(name: str) -> object:
    """``impactchain.api`` (and every other module) after a bare ``import impactchain``,
    imported on first use: matplotlib is loaded only by what draws."""
    if name in _SUBMODULES:
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted([*globals(), *_SUBMODULES])
