"""The HTML report of a campaign's posterior: figures, tables, NetCDF (SPEC §8)."""

from .build import Report, build_report

__all__ = ["Report", "build_report"]
