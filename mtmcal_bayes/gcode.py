"""Reading and writing G-code programs: motion blocks with X Y Z B C F words, all else passed through.

Only what compensation needs is interpreted: ``G00``/``G01`` motion blocks
(modal: a block with axis words after a motion block is one too) in absolute
coordinates.  Comments ``( … )`` and ``; …``, ``%`` and ``O`` lines, M codes and
any other block are kept byte for byte.  Rewriting a block replaces only the
number text of its X, Y, Z words, with the number of decimals the program
used there, so a diff of the compensated program shows the corrections only.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError
from .textfiles import read_text

_WORD = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))?")
_COMMENT = re.compile(r"\([^)]*\)|;.*$")
AXES = ("X", "Y", "Z", "B", "C")
LINEAR = ("X", "Y", "Z")


@dataclass
class Word:
    """One address word: letter, value and where its number text sits in the line."""

    letter: str
    value: float
    start: int  # index of the number text in the line
    end: int
    decimals: int


@dataclass
class Block:
    """One line of the program; ``position`` (X, Y, Z, B, C) mm/deg for motion blocks, else None."""

    number: int  # 1-based line number
    text: str
    words: list[Word] = field(default_factory=list)
    position: tuple | None = None

    @property
    def is_motion(self) -> bool:
        return self.position is not None


@dataclass
class Program:
    """A parsed program; ``motion`` indexes its motion blocks."""

    blocks: list[Block]
    source: str
    newline: str = "\n"

    @property
    def motion(self) -> list[Block]:
        return [b for b in self.blocks if b.is_motion]

    def positions(self) -> np.ndarray:
        """(k, 5) X, Y, Z (mm), B, C (deg) of the motion blocks (modal values filled in)."""
        return np.array([b.position for b in self.motion], dtype=float).reshape(-1, 5)


def _words(line: str, number: int, source: str) -> list[Word]:
    code = _COMMENT.sub(lambda m: " " * len(m.group(0)), line)
    out = []
    for m in _WORD.finditer(code):
        letter = m.group(1).upper()
        if m.group(2) is None:
            rest = code[m.end():].lstrip()
            raise InputError(source, f"line {number}",
                             f"word {letter!r} has no number ({(letter + rest)[:20]!r})")
        text = m.group(2)
        value = float(text)
        if not math.isfinite(value):
            raise InputError(source, f"line {number}", f"word {letter}{text} is not finite")
        decimals = len(text.split(".")[1]) if "." in text else 0
        out.append(Word(letter, value, m.start(2), m.end(2), decimals))
    return out


def parse_program(text: str, source: str = "<program>") -> Program:
    """Parse G-code text; malformed blocks raise :class:`InputError` naming the line."""
    newline = "\r\n" if "\r\n" in text else "\n"
    lines = text.split(newline)
    if lines and lines[-1] == "":
        lines = lines[:-1]
    modal_motion = False
    state: dict[str, float | None] = dict.fromkeys(AXES)
    blocks = []
    for i, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped or stripped[0] in "%(;O":  # blank, tape mark, comment, program number
            blocks.append(Block(i, line))
            continue
        words = _words(line, i, source)
        g = [w.value for w in words if w.letter == "G"]
        if 91 in g:
            raise InputError(source, f"line {i}", "G91 incremental programming is not supported (absolute G90 only)")
        if any(v in (0, 1) for v in g):
            modal_motion = True
        elif any(v in (2, 3) for v in g):
            raise InputError(source, f"line {i}", "circular interpolation (G02/G03) is not supported")
        has_axis = any(w.letter in AXES for w in words)
        if modal_motion and has_axis:
            for w in words:
                if w.letter in AXES:
                    state[w.letter] = w.value
            missing = [a for a in LINEAR if state[a] is None]
            if missing:
                raise InputError(source, f"line {i}", f"position of axis {', '.join(missing)} not known yet "
                                 "(no earlier value in the program)")
            pos = tuple(state[a] if state[a] is not None else 0.0 for a in AXES)
            blocks.append(Block(i, line, words, pos))
        else:
            blocks.append(Block(i, line, words))
    if not any(b.is_motion for b in blocks):
        raise InputError(source, None, "no G00/G01 motion block with X, Y, Z words")
    return Program(blocks, source, newline)


def read_program(path) -> Program:
    return parse_program(read_text(path, "NC program"), str(path))


def _fmt(value: float, decimals: int) -> str:
    s = f"{value:.{decimals}f}"
    return s[1:] if s.startswith("-") and float(s) == 0 else s  # no "-0.0000"


def rewrite(program: Program, xyz: np.ndarray, default_decimals: int = 4) -> str:
    """Program text with the motion blocks' X, Y, Z replaced by ``xyz`` (k, 3) mm; all else unchanged."""
    out = []
    moves = iter(np.asarray(xyz, dtype=float))
    for b in program.blocks:
        if not b.is_motion:
            out.append(b.text)
            continue
        new = dict(zip(LINEAR, next(moves)))
        line = b.text
        present = {w.letter: w for w in b.words}
        dec = max([w.decimals for w in b.words if w.letter in LINEAR] or [default_decimals])
        for w in sorted((w for w in b.words if w.letter in LINEAR), key=lambda w: -w.start):
            line = line[: w.start] + _fmt(new[w.letter], w.decimals) + line[w.end:]
        missing = [a for a in LINEAR if a not in present and _fmt(new[a], dec) != _fmt(b.position[LINEAR.index(a)], dec)]
        if missing:  # modal axis that now moves: its word is added after the block's last word
            last = max(b.words, key=lambda w: w.end)
            shift = len(line) - len(b.text)
            at = last.end + shift
            line = line[:at] + "".join(f" {a}{_fmt(new[a], dec)}" for a in missing) + line[at:]
        out.append(line)
    return program.newline.join(out) + program.newline


def block_line(X, Y, Z, B, C, feed=None, decimals: int = 4, motion: str = "G01") -> str:
    """One motion block, e.g. ``G01 X-390.0000 Y0.0000 Z-112.2605 B0.0000 C0.0000 F2000``."""
    words = [motion] + [f"{a}{_fmt(v, decimals)}" for a, v in zip(AXES, (X, Y, Z, B, C))]
    if feed is not None:
        words.append(f"F{feed:g}")
    return " ".join(words)
