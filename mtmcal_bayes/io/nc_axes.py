"""Motion blocks with any machine's axis letters: writing them, and reading their positions back.

:mod:`mtmcal_bayes.io.gcode` reads and rewrites the thesis machine's programs (axis words X Y Z B C) for
compensation.  A described machine's measuring programs (:mod:`mtmcal_bayes.io.chain_programs`) carry the
description's own letters (``X Y Z A C`` on a trunnion) and a skip move ``G31`` for probing; this module writes
their blocks and reads back what they command, so that tests and callers can put the commanded positions through
a model.  Its reader understands only what those programs contain: ``G00``/``G01`` (modal), ``G31`` (one block),
axis words, comments ``( … )``, and blocks without motion (``G90 G21``, ``M00``, ``M30``), which it skips.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..units import fixed
from .gcode import _words

#: decimals of an axis word: 0.1 µm and 0.0001° (the thesis' Fig 4.30(a))
DECIMALS = 4
#: the motion codes a block of these programs carries
MOTIONS = {0.0: "G00", 1.0: "G01", 31.0: "G31"}


def comment(text: str) -> str:
    """``text`` as one comment block ``(…)``: parentheses inside become brackets (a comment cannot nest them on
    most controls), and only ASCII is kept (``°`` -> ``deg``, ``µm`` -> ``um``)."""
    text = text.replace("(", "[").replace(")", "]").replace("°", " deg").replace("µ", "u").replace("″", " arcsec")
    return "(" + text.encode("ascii", "replace").decode("ascii") + ")"


def axis_letters(desc) -> tuple[str, ...]:
    """The axis words of a described machine's blocks, in ISO word order: ``X Y Z`` then its rotary letters
    alphabetically (``X Y Z A C`` on a trunnion; the thesis machine's ``X Y Z B C``)."""
    return ("X", "Y", "Z") + tuple(sorted(a.letter for a in desc.rotary_axes))


def axis_block(position: dict[str, float], *, motion: str = "G01", feed: float | None = None,
               decimals: int = DECIMALS, note: str = "") -> str:
    """One motion block to ``position`` {letter: value} (mm, degrees) in the order given,
    e.g. ``G01 X0.0000 Y-18.1372 Z-231.8629 A30.0000 C0.0000 F1000``; ``note`` a comment after it."""
    words = [motion] + [f"{a}{fixed(v, decimals)}" for a, v in position.items()]
    if feed is not None:
        words.append(f"F{feed:g}")
    return " ".join(words) + (f" {comment(note)}" if note else "")


@dataclass(frozen=True)
class AxisBlock:
    """One motion block read back: its 1-based ``line``, ``motion`` (``"G00"``, ``"G01"``, ``"G31"``), the
    ``words`` it writes {letter: value} and the ``position`` it commands {letter: value}, mm and degrees (the
    modal value of an axis it leaves out; NaN for one not yet programmed)."""

    line: int
    motion: str
    words: dict
    position: dict


def read_axis_blocks(text: str, letters, source: str = "<program>") -> list[AxisBlock]:
    """The motion blocks of ``text`` whose axis words are among ``letters``, in order (see the module docstring);
    a malformed block is an :class:`~mtmcal_bayes.errors.InputError` naming its line (gcode's tokeniser)."""
    letters = tuple(letters)
    state = dict.fromkeys(letters, np.nan)
    modal = None
    out = []
    for i, line in enumerate(text.splitlines(), start=1):
        stripped = line.strip()
        if not stripped or stripped[0] in "%(;O":
            continue
        words = _words(line, i, source)
        g = [MOTIONS[w.value] for w in words if w.letter == "G" and w.value in MOTIONS]
        axes = {w.letter: w.value for w in words if w.letter in letters}
        if g and g[-1] != "G31":
            modal = g[-1]
        motion = "G31" if "G31" in g else modal
        if not axes or motion is None:
            continue
        state.update(axes)
        out.append(AxisBlock(i, motion, axes, dict(state)))
    return out
