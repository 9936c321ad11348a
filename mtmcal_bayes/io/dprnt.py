"""Reading NC-side text files: DPRNT probe output (thesis Fig 5.13).

A DPRNT file holds one probed point per line, ``X-390.0000 Y0.0000 Z-464.5118
B0.0000 C0.0000``, between ``%`` lines, with optional header lines such as
``Number of Points 40`` and ``Feature Model PLANE``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import InputError
from .textfiles import read_user_text

_WORD = re.compile(r"([A-Z])\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?|[-+]?(?:nan|inf)\b)", re.IGNORECASE)
_COUNT = re.compile(r"^number\s+of\s+points\s+(\d+)\s*$", re.IGNORECASE)
_FEATURE = re.compile(r"^feature\s+model\s+(\S+)\s*$", re.IGNORECASE)
_AXES = ("X", "Y", "Z", "B", "C")


@dataclass
class DprntPoints:
    """Probed points of a DPRNT file.

    ``xyz``: (n, 3) machine coordinates, mm; ``bc``: (n, 2) B and C, degrees;
    ``lines``: (n,) line numbers; ``declared``: the header's point count, if any.
    """

    xyz: np.ndarray
    bc: np.ndarray
    lines: np.ndarray
    declared: int | None = None
    feature: str | None = None
    source: str = ""


def read_dprnt(path: str | Path) -> DprntPoints:
    """Read a DPRNT output file; malformed lines raise an error naming the line."""
    text = read_user_text(path, "DPRNT file")
    return parse_dprnt(text, str(path))


def parse_dprnt(text: str, source: str = "<dprnt>") -> DprntPoints:
    if not text.strip():
        raise InputError(source, None, "empty file (expected DPRNT lines such as 'X-390.0000 Y0.0000 Z-464.5118')")
    xyz, bc, lines = [], [], []
    declared = feature = None
    for no, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line == "%":
            continue
        if m := _COUNT.match(line):
            declared = int(m.group(1))
            continue
        if m := _FEATURE.match(line):
            feature = m.group(1)
            continue
        words = {}
        pos = 0
        for m in _WORD.finditer(line):
            if line[pos:m.start()].strip():
                break
            letter = m.group(1).upper()
            if letter not in _AXES:
                raise InputError(source, f"line {no}", f"word {letter}{m.group(2)} is not a coordinate "
                                 f"(expected {' '.join(_AXES)}): {raw.strip()!r}")
            if letter in words:
                raise InputError(source, f"line {no}", f"{letter} appears twice: {raw.strip()!r}")
            words[letter] = m.group(2)
            pos = m.end()
        if pos != len(line) or not words:
            raise InputError(source, f"line {no}", f"not a DPRNT point line: {raw.strip()!r}")
        missing = [a for a in "XYZ" if a not in words]
        if missing:
            raise InputError(source, f"line {no}", f"point without {'/'.join(missing)}: {raw.strip()!r}")
        vals = {}
        for a, v in words.items():
            f = float(v)
            if not math.isfinite(f):
                raise InputError(source, f"line {no}", f"{a} is {v}, not a finite coordinate")
            vals[a] = f
        xyz.append([vals["X"], vals["Y"], vals["Z"]])
        bc.append([vals.get("B", 0.0), vals.get("C", 0.0)])
        lines.append(no)
    if not xyz:
        raise InputError(source, None, "no probed points found")
    return DprntPoints(np.array(xyz), np.array(bc), np.array(lines), declared, feature, source)
