"""A package's public names imported on first use (PEP 562), for the packages whose ``__init__`` would otherwise load
heavy modules (numpy, ArviZ) that many commands never need."""

from __future__ import annotations

import importlib


def lazy_names(package: str, home: dict[str, str], namespace: dict, *, modules: tuple[str, ...] = ()):
    """The ``(__getattr__, __dir__)`` of ``package`` whose names ``home`` {name: submodule} are imported from their
    submodule on first use and kept in ``namespace`` (the package's globals); ``modules``: submodules that are
    names themselves."""

    def __getattr__(name: str):
        if name in modules:
            return importlib.import_module(f".{name}", package)
        if name not in home:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f".{home[name]}", package), name)
        namespace[name] = value
        return value

    def __dir__():
        return sorted(set(namespace) | set(namespace.get("__all__", ())))

    return __getattr__, __dir__


__all__ = ["lazy_names"]
