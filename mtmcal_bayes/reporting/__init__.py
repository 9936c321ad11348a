"""The HTML report of a campaign's posterior: figures, tables, NetCDF (SPEC §8).

:func:`build_report` and :class:`Report` are loaded when first asked for: importing a figure module or the
report's first steps (:mod:`.start`) does not import the report's computation (:mod:`.build`)."""

__all__ = ["Report", "build_report"]


def __getattr__(name: str):
    if name in __all__:
        from . import build

        return getattr(build, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
