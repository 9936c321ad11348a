"""Reading and writing G-code programs: motion blocks with X Y Z B C F words, all else passed through.

Only what compensation needs is interpreted: ``G00``/``G01`` motion blocks
(modal: a block with axis words after a motion block is one too) in absolute
coordinates.  Comments ``( … )`` and ``; …``, ``%`` and ``O`` lines, M codes and
any other block are kept byte for byte.  Rewriting a block replaces only the
number text of its X, Y, Z words that change, with the number of decimals the
program used there but at least 3 (1 µm: ``X100.`` or ``X12.5`` would round the
correction away), so a diff of the compensated program shows the corrections only.

Blocks whose X is not a position (``G04`` dwell, ``G10.9``) pass through, as
do ``G28``/``G30``/``G53`` moves (the positions of their axes are unknown
after them).  What compensation cannot interpret is an error naming the line:
``G91``, ``G20``, ``G02``/``G03``, ``G10``/``G52``/``G92``, an axis programmed
twice in a block, a word other than ``G N X Y Z B C F M S T H D`` in a motion
block (an ``A``/``U``/``V``/``W`` axis, ``O`` typed for a zero), and any text
that is not an address word or a comment (decimal commas, macros).  A described
machine's program is read with its own rotary letters (``rotary=("A", "C")`` on a
trunnion: there ``B`` is the word refused) and every axis required in every block.

Axis words without a decimal point (``X100``, ``B90``) mean different things on
different controls: with decimal-point programming (Fanuc and alike) ``X100`` is
100 least-input increments, 0.100 mm at 1 µm, and ``B90`` 0.090° at 0.001°; on
others (calculator-type input) 100 mm and 90°.  The rule is the control's, so
it applies to every X, Y, Z, B, C word whose value compensation uses as a
position (those of G00/G01 blocks): with ``integer_unit=None`` such a word is an
error naming the line; ``"um"`` reads it in increments of 1/1000 of the unit
(1 µm, 0.001°), ``"mm"`` in whole units (mm, °).  B and C are included because a
misread B angle moves the tool as much as a misread X.  A zero (``X0``, ``C0``)
is accepted whatever ``integer_unit`` is: it is zero under either reading, and
refusing it would refuse common programs for a word that cannot be misread.
Words that are not positions are never affected: G, M, N, F, S, T, H, D, the X
of a ``G04`` dwell or ``G10.9``, the axes of ``G28``/``G30``/``G53`` (passed
through).  A word read with ``integer_unit`` and unchanged by compensation keeps
its text; a changed one is written in mm (degrees) with a decimal point.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

import numpy as np

from .. import units
from ..errors import InputError, ParameterError
from ..units import fixed
from .textfiles import read_user_text

_WORD = re.compile(r"([A-Za-z])\s*([-+]?(?:\d+\.?\d*|\.\d+))?")
_COMMENT = re.compile(r"\([^)]*\)|;.*$")
AXES = ("X", "Y", "Z", "B", "C")
LINEAR = ("X", "Y", "Z")
#: a changed X/Y/Z is written with at least this many decimals (1 µm): X100. or X12.5 would round a correction away
MIN_DECIMALS = 3
OTHER_AXES = ("A", "U", "V", "W")  # axes the model does not have (U/W: incremental X/Z on lathe controls)
MOTION_WORDS = frozenset("GNXYZBCFMSTHD")  # the words a G00/G01 block may carry here
_PASS_G = (4.0, 10.9)  # dwell, radius/diameter switch: their X is not a position; the block passes through
_MACHINE_G = (28.0, 30.0, 53.0)  # reference point / machine coordinates: passed through, those axes' positions unknown after
_FRAME_G = (10.0, 52.0, 92.0)  # set offsets or shift the coordinate system: later positions cannot be interpreted
#: counts per mm (linear) or degree (rotary) of an axis word without a decimal point, by ``integer_unit``:
#: "um" least input increments of 1/1000 of the unit (1 µm, 0.001°), "mm" whole units (mm, °).  A division by
#: 1000.0 gives the double nearest the decimal, as ``X0.123`` does (a product with 0.001 misses it by an ulp)
INTEGER_UNITS = {"um": units.from_internal(1.0, "um"), "mm": 1.0}
#: decimals a word read with ``integer_unit`` carries (the increment's): a changed one is written with them, at least
_INTEGER_DECIMALS = {"um": 3, "mm": 0}


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
    axes: tuple[str, ...] = AXES  # the letters of each block's position, in order


    @property
    def motion(self) -> list[Block]:
        return [b for b in self.blocks if b.is_motion]

    def positions(self) -> np.ndarray:
        """(k, a) positions of the motion blocks in the order of :attr:`axes` (default X, Y, Z mm, B, C deg; modal
        values filled in)."""
        return np.array([b.position for b in self.motion], dtype=float).reshape(-1, len(self.axes))


def _stray(code: str, start: int, end: int, *, number: int, source: str) -> None:
    """Text between two words must be blank (a leading ``/`` block delete aside): nothing is skipped silently."""
    i = start
    while i < end and code[i].isspace():
        i += 1
    if start == 0 and i < end and code[i] == "/":
        i += 1
        while i < end and code[i].isspace():
            i += 1
    if i >= end:
        return
    ch = code[i]
    if ch == "(":
        why = "comment '(' is not closed"
    elif ch in ",.":
        why = f"unexpected {ch!r} after a number (a decimal comma, or two decimal points?)"
    elif ch in "#[]=":
        why = f"unexpected {ch!r}: macro variables and expressions are not supported"
    else:
        why = f"unexpected character {ch!r}"
    raise InputError(source, f"line {number}", f"{why} at column {i + 1}")


def _words(line: str, number: int, source: str) -> list[Word]:
    code = _COMMENT.sub(lambda m: " " * len(m.group(0)), line)
    out = []
    pos = 0
    for m in _WORD.finditer(code):
        _stray(code, pos, m.start(), number=number, source=source)
        pos = m.end()
        letter = m.group(1).upper()
        if m.group(2) is None:
            rest = code[m.end():].lstrip()
            raise InputError(source, f"line {number}",
                             f"word {letter!r} has no number ({(letter + rest)[:20]!r})")
        text = m.group(2)
        value = float(text)
        if not math.isfinite(value):
            shown = text if len(text) <= 24 else text[:20] + "…"
            raise InputError(source, f"line {number}", f"word {letter}{shown} is not finite")
        decimals = len(text.split(".")[1]) if "." in text else 0
        out.append(Word(letter, value, m.start(2), m.end(2), decimals))
    _stray(code, pos, len(code), number=number, source=source)
    return out


def _integer_words(words: list[Word], line: str, integer_unit: str | None, *, number: int,
                   source: str, axes: tuple[str, ...] = AXES) -> list[Word]:
    """The words of a motion block with each nonzero X Y Z B C written without a decimal point read in
    ``integer_unit`` (mm, degrees; see the module docstring); without ``integer_unit`` such a word is an error."""
    out = []
    for w in words:
        text = line[w.start:w.end]
        if w.letter in axes and "." not in text and w.value != 0:
            if integer_unit is None:
                unit, step = (" mm", "1 µm") if w.letter in LINEAR else ("°", "0.001°")
                small = w.value / INTEGER_UNITS["um"]  # the value at 1/1000 of the unit per count
                raise InputError(source, f"line {number}", (
                    f"{w.letter}{text} has no decimal point: many controls read it as {text} least-input "
                    f"increments ({small:g}{unit} at {step}), not {text}{unit}; write {w.letter}{text}. "
                    "or give the control's integer unit (um or mm)"))
            w = Word(w.letter, w.value / INTEGER_UNITS[integer_unit], w.start, w.end,
                     _INTEGER_DECIMALS[integer_unit])
        out.append(w)
    return out


def parse_program(text: str, source: str = "<program>", *, integer_unit: str | None = None,
                  rotary: tuple[str, ...] = ("B", "C"), required: tuple[str, ...] = LINEAR) -> Program:
    """Parse G-code text; malformed blocks raise :class:`InputError` naming the line.

    ``integer_unit``: how X Y Z B C words without a decimal point are read — ``"um"`` (counts of 1 µm /
    0.001°), ``"mm"`` (mm / degrees) or ``None`` (an error; see the module docstring).  ``rotary``: the rotary
    axis letters of the machine (default the thesis machine's B, C; a described machine's, e.g. ``("A", "C")``);
    ``required``: the axes whose position every motion block must know (default X, Y, Z; a rotary axis not yet
    programmed is 0 otherwise).
    """
    axes = LINEAR + tuple(rotary)
    motion_words = (MOTION_WORDS - set(AXES)) | set(axes)
    other_axes = tuple(a for a in OTHER_AXES + AXES if a not in axes)
    if integer_unit is not None and integer_unit not in INTEGER_UNITS:
        raise ParameterError("integer_unit", f"expected one of {', '.join(map(repr, INTEGER_UNITS))} or None "
                             f"(refuse axis words without a decimal point), got {integer_unit!r}")
    if not text.strip():
        raise InputError(source, None, "empty file (expected an NC program with G00/G01 X Y Z blocks)")
    newline = "\r\n" if "\r\n" in text else "\r" if "\r" in text and "\n" not in text else "\n"
    lines = text.split(newline)
    if lines and lines[-1] == "":
        lines = lines[:-1]
    modal_motion = False
    state: dict[str, float | None] = dict.fromkeys(axes)
    blocks = []
    for i, line in enumerate(lines, start=1):
        stripped = line.strip()
        if not stripped or stripped[0] in "%(;O<":  # blank, tape mark, comment, program number or <name>
            blocks.append(Block(i, line))
            continue
        words = _words(line, i, source)
        g = [w.value for w in words if w.letter == "G"]
        if 91 in g:
            raise InputError(source, f"line {i}", "G91 incremental programming is not supported (absolute G90 only)")
        if 20 in g:
            raise InputError(source, f"line {i}", "G20 inch programming is not supported (millimetres, G21, only)")
        if frame := [v for v in g if v in _FRAME_G]:
            raise InputError(source, f"line {i}", f"G{frame[0]:g} sets offsets or shifts the coordinate system "
                             "inside the program: the positions after it cannot be compensated")
        seen = [w.letter for w in words if w.letter in axes]
        if twice := next((a for a in axes if seen.count(a) > 1), None):
            raise InputError(source, f"line {i}", f"axis {twice} is programmed twice in one block")
        if any(v in _PASS_G for v in g):
            blocks.append(Block(i, line, words))
            continue
        if any(v in _MACHINE_G for v in g):
            for a in seen:
                state[a] = None
            blocks.append(Block(i, line, words))
            continue
        if any(v in (0, 1) for v in g):
            modal_motion = True
        elif any(v in (2, 3) for v in g):
            raise InputError(source, f"line {i}", "circular interpolation (G02/G03) is not supported")
        has_axis = any(w.letter in axes for w in words)
        other = next((w for w in words if w.letter not in motion_words), None)
        if modal_motion and other is not None and (has_axis or other.letter in other_axes):
            hint = (f"axis {other.letter} is not one of {' '.join(axes)}; U/W are incremental X/Z on lathe controls"
                    if other.letter in other_axes else "a letter typed for a digit?")
            raise InputError(source, f"line {i}", f"word {other.letter}{line[other.start:other.end]} is not "
                             f"expected in a G00/G01 block ({hint})")
        if modal_motion and has_axis:
            words = _integer_words(words, line, integer_unit, number=i, source=source, axes=axes)
            for w in words:
                if w.letter in axes:
                    state[w.letter] = w.value
            missing = [a for a in axes if a in required and state[a] is None]
            if missing:
                raise InputError(source, f"line {i}", f"position of axis {', '.join(missing)} not known yet "
                                 "(no earlier value in the program)")
            pos = tuple(state[a] if state[a] is not None else 0.0 for a in axes)
            blocks.append(Block(i, line, words, pos))
        else:
            blocks.append(Block(i, line, words))
    if not any(b.is_motion for b in blocks):
        raise InputError(source, None, "no G00/G01 motion block with X, Y, Z words")
    return Program(blocks, source, newline, axes)


def read_program(path, *, integer_unit: str | None = None, rotary: tuple[str, ...] = ("B", "C"),
                 required: tuple[str, ...] = LINEAR) -> Program:
    """The NC program at ``path`` (see :func:`parse_program` for ``integer_unit``, ``rotary`` and ``required``)."""
    return parse_program(read_user_text(path, "NC program"), str(path), integer_unit=integer_unit, rotary=rotary,
                         required=required)


def rewrite(program: Program, xyz: np.ndarray, default_decimals: int = 4) -> str:
    """Program text with the motion blocks' X, Y, Z replaced by ``xyz`` (k, 3) mm; all else unchanged.

    An axis a block leaves modal gets a word when its new value differs from its
    old one, or from the value the rewritten program carries into the block (an
    earlier block was corrected and this one is not).
    """
    out = []
    moves = iter(np.asarray(xyz, dtype=float))
    modal: dict[str, float | None] = dict.fromkeys(LINEAR)  # X, Y, Z of the rewritten program so far
    for b in program.blocks:
        if not b.is_motion:
            if any(w.letter == "G" and w.value in _MACHINE_G for w in b.words):  # positions unknown after it
                modal.update({w.letter: None for w in b.words if w.letter in LINEAR})
            out.append(b.text)
            continue
        new = dict(zip(LINEAR, next(moves)))
        line = b.text
        present = {w.letter: w for w in b.words}
        dec = max(max([w.decimals for w in b.words if w.letter in LINEAR], default=default_decimals), MIN_DECIMALS)
        for w in sorted((w for w in b.words if w.letter in LINEAR), key=lambda w: -w.start):
            if new[w.letter] == w.value:  # unchanged: keep the text as written (X+1.5, X100., X-0.000)
                modal[w.letter] = w.value
                continue
            text = fixed(new[w.letter], max(w.decimals, MIN_DECIMALS))
            line = line[: w.start] + text + line[w.end:]
            modal[w.letter] = float(text)
        missing = [a for a in LINEAR if a not in present and (modal[a] is None or len(
            {fixed(new[a], dec), fixed(modal[a], dec), fixed(b.position[LINEAR.index(a)], dec)}) > 1)]
        if missing:  # modal axis that now moves: its word is added after the block's last word
            last = max(b.words, key=lambda w: w.end)
            shift = len(line) - len(b.text)
            at = last.end + shift
            line = line[:at] + "".join(f" {a}{fixed(new[a], dec)}" for a in missing) + line[at:]
            modal.update({a: float(fixed(new[a], dec)) for a in missing})
        out.append(line)
    return program.newline.join(out) + program.newline


def block_line(position, *, feed=None, decimals: int = 4, motion: str = "G01") -> str:
    """One motion block to ``position`` = (X, Y, Z, B, C), mm and degrees,
    e.g. ``G01 X-390.0000 Y0.0000 Z-112.2605 B0.0000 C0.0000 F2000``; with ``decimals=0`` the numbers keep
    their decimal point (``X-390.``): without it many controls read least-input increments."""
    point = "." if decimals == 0 else ""
    words = [motion] + [f"{a}{fixed(v, decimals)}{point}" for a, v in zip(AXES, position)]
    if feed is not None:
        words.append(f"F{feed:g}")
    return " ".join(words)
