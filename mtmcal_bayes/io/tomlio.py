"""Minimal TOML writing (the standard library only reads TOML).

Writes the value types campaign files use: tables, arrays of tables, strings,
booleans, integers, floats (shortest form, or a fixed number of decimals via
:class:`Fixed`) and nested arrays of those.
"""

from __future__ import annotations

import datetime
import math
import re
from dataclasses import dataclass

from ..units import fixed

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")


@dataclass(frozen=True)
class Fixed:
    """A float written with exactly ``decimals`` digits after the point (e.g. as printed in a thesis table)."""

    value: float
    decimals: int


def _key(k: str) -> str:
    return k if _BARE_KEY.match(k) else _string(k)


def _float(x: float) -> str:
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    # 12 significant digits: exact for measured data, and undoes the round-off of mm<->µm scaling
    s = repr(float(f"{x:.12g}"))
    return s if ("." in s or "e" in s or "inf" in s or "nan" in s) else s + ".0"


def _string(s: str) -> str:
    """A TOML basic string: backslash, quote and every control character escaped (tab may stay)."""
    out = s.replace("\\", "\\\\").replace('"', '\\"')
    return '"' + "".join(c if c == "\t" or (ord(c) >= 0x20 and ord(c) != 0x7F) else f"\\u{ord(c):04X}"
                         for c in out) + '"'


def _value(v) -> str:
    if isinstance(v, Fixed):
        return fixed(v.value, v.decimals)
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, int):
        return str(v)
    if isinstance(v, float):
        return _float(v)
    if isinstance(v, str):
        return _string(v)
    if isinstance(v, datetime.datetime):  # a date-time at midnight without offset is written as a TOML date
        midnight = v.tzinfo is None and v.time() == datetime.time()
        return v.date().isoformat() if midnight else v.isoformat()
    if isinstance(v, datetime.date):
        return v.isoformat()
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if hasattr(v, "tolist"):  # numpy arrays and scalars
        return _value(v.tolist())
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def _is_table(v) -> bool:
    return isinstance(v, dict)


def _is_table_array(v) -> bool:
    return isinstance(v, list) and len(v) > 0 and all(isinstance(x, dict) for x in v)


def dumps(data: dict) -> str:
    """Serialise a nested dict to TOML text."""
    out: list[str] = []
    _emit_table(data, [], out)
    return "\n".join(out).lstrip("\n") + "\n"


def _emit_table(table: dict, path: list[str], out: list[str]) -> None:
    for k, v in table.items():
        if not (_is_table(v) or _is_table_array(v)):
            out.append(f"{_key(k)} = {_value(v)}")
    for k, v in table.items():
        sub = path + [_key(k)]
        if _is_table(v):
            scalars = any(not (_is_table(x) or _is_table_array(x)) for x in v.values())
            if scalars or not v:
                out.append("")
                out.append(f"[{'.'.join(sub)}]")
            _emit_table(v, sub, out)
        elif _is_table_array(v):
            for item in v:
                out.append("")
                out.append(f"[[{'.'.join(sub)}]]")
                _emit_table(item, sub, out)
