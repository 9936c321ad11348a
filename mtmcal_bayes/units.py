"""Unit conversion at the edges of the package.

Internally every length is in millimetres and every angle in radians.  Files,
tables and plots use the units a calibration engineer reads: micrometres (µm)
for small lengths, arc seconds (″) for small angles, millimetres for lever arms,
degrees for axis positions.  Keys in files carry their unit as a suffix
(``_mm``, ``_um``, ``_arcsec``, ``_deg``).
"""

from __future__ import annotations

import math

import numpy as np

#: radians per arc second
ARCSEC = math.pi / 648000.0
#: millimetres per micrometre
UM = 1e-3
#: radians per degree
DEG = math.pi / 180.0

#: internal units per one display unit, keyed by the file-key suffix / JSON unit name
_SCALE = {"mm": 1.0, "um": UM, "arcsec": ARCSEC, "deg": DEG, "rad": 1.0}

#: display symbol of each unit
SYMBOL = {"mm": "mm", "um": "µm", "arcsec": "″", "deg": "°", "rad": "rad"}


#: counts as prose writes them
_WORDS = ("no", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten", "eleven", "twelve")


def in_words(n: int) -> str:
    """A count as a sentence says it: ``"eight"`` up to twelve, digits beyond (``"13"``)."""
    return _WORDS[n] if 0 <= n < len(_WORDS) else str(n)


def fixed(value: float, decimals: int) -> str:
    """``value`` with ``decimals`` digits after the point, never ``-0.000`` (files re-read ``-0`` as an integer,
    and an NC program should not show a sign for zero)."""
    s = f"{value:.{decimals}f}"
    return s[1:] if s.startswith("-") and float(s) == 0 else s


def to_internal(value, unit: str):
    """Convert ``value`` (scalar or array) from ``unit`` to mm / rad."""
    if np.isscalar(value):
        return float(value) * _SCALE[unit]
    return np.asarray(value, dtype=float) * _SCALE[unit]


def from_internal(value, unit: str):
    """Convert ``value`` (scalar or array) from mm / rad to ``unit``."""
    if np.isscalar(value):
        return float(value) / _SCALE[unit]
    return np.asarray(value, dtype=float) / _SCALE[unit]


def split_unit_key(key: str) -> tuple[str, str | None]:
    """Split a file key such as ``"beta_XB_arcsec"`` into ``("beta_XB", "arcsec")``.

    Returns ``(key, None)`` when the key carries no known unit suffix.
    """
    for unit in ("arcsec", "um", "mm", "deg"):
        if key.endswith("_" + unit):
            return key[: -len(unit) - 1], unit
    return key, None
