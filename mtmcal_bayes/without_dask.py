"""A command-line process without Dask: what xarray sees when Dask is not installed.

Dask is installed for fleets and batch validation, and xarray then imports it on the first InferenceData
(``dask``, ``dask.array``: to recognise Dask arrays among numpy ones) and on writing NetCDF
(``dask.distributed``: to recognise its scheduler and lock).  For a command that has no Dask array and no
scheduler (every one but ``fleet`` and ``validate``) that is 0.7 s of a 2.4 s ``sample``.

:func:`hide_dask` makes this process look like one without Dask:

* a meta-path finder refuses ``dask``, its submodules and ``distributed`` (an ``ImportError``: what xarray,
  emcee and ArviZ take as "not installed");
* xarray asks ``importlib.util.find_spec("dask")`` through ``xarray.namedarray.utils.module_available``, which a
  refusing finder would turn into an exception, so that function is wrapped as its module is loaded to answer
  "not available" for Dask (every other module is asked as before).  Should a later xarray move the function,
  the wrapper is simply not applied and the finder's refusal is met where xarray imports Dask inside
  ``try``/``except ImportError`` — the command test of every command in a subprocess shows whether that holds.

A ``None`` entry in ``sys.modules`` would refuse the imports too, but breaks SciPy, whose array-API checks look
modules up there (``stats.lognorm.logpdf`` failed with it).  Only the command line calls this, and only where the
process is the command (``main()`` without arguments), never in a caller's process.
"""

from __future__ import annotations

import importlib.machinery
import sys

#: the top-level packages refused, with their submodules
HIDDEN = ("dask", "distributed")
#: the xarray module whose ``module_available`` is told that Dask is not installed
XARRAY_UTILS = "xarray.namedarray.utils"


def _hidden(name: str) -> bool:
    return name.split(".", 1)[0] in HIDDEN


def _tell_xarray(module) -> None:
    """Wrap ``module.module_available`` (xarray's "is this module installed?") to answer False for Dask."""
    asked = getattr(module, "module_available", None)
    if asked is None:
        return

    def module_available(name: str, minversion: str | None = None) -> bool:
        return False if _hidden(name) else asked(name, minversion)

    module.module_available = module_available


class _WithoutDask:
    """The meta-path finder of :func:`hide_dask`."""

    def __init__(self, name: str):
        self.name = name  # the command, named in the refusal

    def find_spec(self, name, path=None, target=None):
        if _hidden(name):
            raise ModuleNotFoundError(f"No module named {name!r} (not used by {self.name})", name=name)
        if name != XARRAY_UTILS:
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None or not hasattr(spec.loader, "exec_module"):
            return spec
        load = spec.loader.exec_module

        def exec_module(module):
            load(module)
            _tell_xarray(module)

        spec.loader.exec_module = exec_module
        return spec


def hide_dask(command: str) -> bool:
    """Keep Dask out of this process from now on (module docstring); False (and nothing done) when Dask or xarray
    is already imported, where hiding it could only break what holds it."""
    if any(_hidden(name) for name in sys.modules) or XARRAY_UTILS in sys.modules:
        return False
    sys.meta_path.insert(0, _WithoutDask(command))
    return True
