"""Typed, validated access to parsed TOML with one-line errors naming the file and the key."""

from __future__ import annotations

import math
import tomllib

import numpy as np

from ..errors import InputError

_MISSING = object()

class TomlReader:
    """Typed access to a parsed TOML document with errors naming file and key."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, key: str | None, message: str):
        raise InputError(self.source, key, message)

    def _lookup(self, table: dict, key: str, path: str, *, required: bool, what: str):
        """``(full key, value)``; value ``_MISSING`` when absent and not required."""
        full = f"{path}.{key}" if path else key
        if key not in table:
            if required:
                self.fail(full, f"missing {what}".rstrip())
            return full, _MISSING
        return full, table[key]

    def table(self, parent: dict, key: str, path: str, required: bool = True) -> dict | None:
        full, v = self._lookup(parent, key, path, required=required, what="table")
        if v is _MISSING:
            return None
        if not isinstance(v, dict):
            self.fail(full, f"expected a table, got {kind_of(v)}")
        return v

    def subtables(self, parent: dict, key: str, path: str, *, allowed, what: str):
        """Yield ``(id, full key, table)`` for each ``[path.key.<id>]``; at least one is required."""
        tables = self.table(parent, key, path)
        if not tables:
            self.fail(f"{path}.{key}", f"at least one {what} is needed")
        for oid, sub in tables.items():
            full = f"{path}.{key}.{oid}"
            if not isinstance(sub, dict):
                self.fail(full, f"expected a table, got {kind_of(sub)}")
            self.check_keys(sub, allowed, full)
            yield oid, full, sub

    def check_keys(self, table: dict, allowed, path: str) -> None:
        for k in table:
            if k not in allowed:
                where = f"{path}.{k}" if path else k
                self.fail(where, f"unknown key (expected one of: {', '.join(sorted(allowed))})")

    def string(self, table: dict, key: str, path: str, *, required: bool = False, default: str = "") -> str:
        full, v = self._lookup(table, key, path, required=required, what="")
        if v is _MISSING:
            return default
        if not isinstance(v, str):
            self.fail(full, f"expected a string, got {kind_of(v)}")
        return v

    def number(self, table: dict, key: str, path: str, *, required: bool = True, positive: bool = False,
               nonnegative: bool = False, default: float | None = None) -> float | None:
        full, v = self._lookup(table, key, path, required=required, what="")
        if v is _MISSING:
            return default
        return self._check_number(v, full, positive, nonnegative)

    def _check_number(self, v, full: str, positive: bool = False, nonnegative: bool = False) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(full, f"expected a number, got {kind_of(v)}")
        v = float(v)
        if math.isnan(v):
            self.fail(full, "NaN is not a valid value")
        if math.isinf(v):
            self.fail(full, "infinite value")
        if positive and v <= 0:
            self.fail(full, f"must be positive, got {v:g}")
        if nonnegative and v < 0:
            self.fail(full, f"must not be negative, got {v:g}")
        return v

    def array(self, table: dict, key: str, path: str, shape: tuple, *, required: bool = True) -> np.ndarray | None:
        """Numeric array of the given shape; ``None`` entries in ``shape`` match any length >= 1."""
        full, v = self._lookup(table, key, path, required=required, what="")
        if v is _MISSING:
            return None
        out = self._nested(v, full, len(shape))
        arr = np.array(out, dtype=float)
        if arr.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, arr.shape)):
            want = " x ".join("n" if s is None else str(s) for s in shape)
            self.fail(full, f"expected an array of shape {want}, got {' x '.join(map(str, arr.shape)) or 'a scalar'}")
        if arr.size == 0:
            self.fail(full, "empty array")
        return arr

    def _nested(self, v, full: str, depth: int):
        if depth == 0:
            return self._check_number(v, full)
        if not isinstance(v, list):
            self.fail(full, f"expected an array, got {kind_of(v)}")
        if not v:
            self.fail(full, "empty array")
        items = [self._nested(x, f"{full}[{i}]", depth - 1) for i, x in enumerate(v)]
        if depth > 1 and len({len(x) for x in items}) > 1:
            self.fail(full, "rows of different lengths")
        return items


def kind_of(v) -> str:
    """How a TOML value is named in an error message."""
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, (int, float)):
        return "a number"
    if isinstance(v, str):
        return f"the string {v!r}"
    if isinstance(v, list):
        return "an array"
    if isinstance(v, dict):
        return "a table"
    return type(v).__name__


def parse_toml(text: str, source: str, empty_hint: str | None = None) -> dict:
    """The TOML document ``text``; malformed TOML (or, with ``empty_hint``, an empty file) is an
    :class:`InputError` naming ``source``.  ``empty_hint`` says what the file should hold."""
    if empty_hint is not None and not text.strip():
        raise InputError(source, None, f"empty file (expected {empty_hint})")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(source, None, f"malformed TOML: {exc}") from None
