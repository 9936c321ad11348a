"""``[reported]``: the values the thesis published (Table 4.5, ball bar; Table 5.3, touch probe), each with the
decimals it was printed with, read into the campaign's ``reported`` for the identification's tables to set beside
their recomputation."""

from __future__ import annotations

import re

from ... import units
from ...campaign import ReportedValue
from ...io.toml_reader import TomlReader, kind_of
from ...parameters import QUANTITIES

_HEADER = re.compile(r"^\s*\[\s*([^\[\]]+?)\s*\]\s*(#.*)?$")
_NUMBER = re.compile(r"^\s*([A-Za-z0-9_-]+)\s*=\s*([-+]?\d[\d_]*(?:\.(\d[\d_]*))?)\s*(#.*)?$")


def printed_decimals(text: str, table: str) -> dict[str, int]:
    """Decimals written for each plain number key of ``[table]`` in TOML ``text``.

    Used to know how a published value was rounded (``1.10`` has two
    decimals, which ``tomllib`` forgets).
    """
    current = None
    found: dict[str, int] = {}
    for line in text.splitlines():
        h = _HEADER.match(line)
        if h:
            current = h.group(1).replace(" ", "")
            continue
        if current == table:
            m = _NUMBER.match(line)
            if m:
                found[m.group(1)] = len((m.group(3) or "").replace("_", ""))
    return found


def read_reported(r: TomlReader, t: dict, text: str) -> dict[str, dict[str, ReportedValue]]:
    """``[reported.<method>]`` tables of the campaign TOML ``text`` (``t``: ``[reported]`` as parsed): each value by
    its canonical deviation name, in internal units, with its printed decimals (2 where they cannot be seen)."""
    out: dict[str, dict[str, ReportedValue]] = {}
    for method, vals in t.items():
        path = f"reported.{method}"
        if not isinstance(vals, dict):
            r.fail(path, f"expected a table, got {kind_of(vals)}")
        decimals = printed_decimals(text, path)
        out[method] = {}
        for key in vals:
            name, unit = units.split_unit_key(key)
            q = QUANTITIES.get(name)
            if q is None or unit != q.unit:
                r.fail(f"{path}.{key}", "unknown quantity: expected <name>_arcsec for angles or <name>_um "
                       "for lengths, with a canonical deviation name")
            v = r.number(vals, key, path)
            out[method][name] = ReportedValue(units.to_internal(v, unit), unit, decimals.get(key, 2))
    return out
