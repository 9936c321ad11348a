"""Data shipped with the package: the thesis campaign and its NC / DPRNT files.

The INTEGREX i-200 campaign of the thesis (Tables 4.2–4.5, 5.1–5.3) is the
default campaign of every command.  Nothing here reads outside the package.
"""

from __future__ import annotations

from importlib import resources

BUILTIN_CAMPAIGN = "integrex_i200.toml"
BUILTIN_LABEL = "<built-in integrex_i200.toml>"


def data_path(name: str):
    """A traversable path to a shipped data file (``fig4_30a_bx_original.nc``, ...)."""
    return resources.files(__name__).joinpath(name)


def builtin_text(name: str) -> str:
    """Text of a shipped data file (UTF-8)."""
    return data_path(name).read_text(encoding="utf-8")


def builtin_campaign_text() -> tuple[str, str]:
    """Text of the built-in thesis campaign and the label used for it in messages."""
    return builtin_text(BUILTIN_CAMPAIGN), BUILTIN_LABEL
