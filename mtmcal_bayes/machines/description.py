"""A machine tool described, not coded (SPEC §19): its kinematic chain, axis lines, spindle and travels.

The configuration string is the thesis' Fig 2.1 / ISO 10791 notation, read from the workpiece to the tool:
``"w-C'bZYXB(C1)-t"`` is workpiece, C table (primed: it moves the workpiece), bed, then Z, Y, X, the B head
and the spindle ``(C1)`` carrying the tool.  :class:`MachineDescription` keeps the two sides as chains from the
bed outwards: ``work_chain`` (bed → C → workpiece) and ``tool_chain`` (bed → Z → Y → X → B → spindle).

Frame: right-handed, the machine's; commands are the positions of the axes (mm, rad); at the home pose (all
axes at 0) the description is the nominal machine.  A primed linear axis moves the workpiece the opposite way,
so that a positive command moves the tool positively relative to the workpiece (ISO 841), whichever side moves.

What the model assumes and this module enforces: the three linear axes X, Y, Z are all present, each sits
nearer the bed than every rotary axis of its side (the usual build; a linear axis carried by a rotary one is
not supported).  A rotary axis or the spindle may lie along any unit direction at the home pose: one along a
frame axis keeps ISO 230-7's frame names for its location errors, an inclined one has the basis of
:func:`inclined_basis` (SPEC §21).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: frame axes, and the rotary letter turning about each
FRAME = "XYZ"
ROTARY_ABOUT = {"X": "A", "Y": "B", "Z": "C"}
FRAME_OF_ROTARY = {v: k for k, v in ROTARY_ABOUT.items()}
LINEAR = tuple(FRAME)
ROTARY = tuple(ROTARY_ABOUT.values())
#: the spindle's token in the configuration string (a spindle without angle control)
SPINDLE = "C1"
#: how the squareness of the linear axes acts: ISO 230-1's tilted direction of motion, or the thesis'
#: rigid rotation of what the axis carries (its M_XY, M_YZ)
SQUARENESS = ("motion", "rigid")

Fail = Callable[[str, str], None]


@dataclass(frozen=True)
class Axis:
    """One axis of the chain.

    ``direction`` (3,) unit vector at the home pose (a linear axis: its frame axis); ``point`` (3,) mm, a
    point of a rotary axis' nominal line at the home pose (zeros for a linear axis); ``travel`` (min, max) in
    mm or rad, or None; ``work_side``: it moves the workpiece (primed in the configuration).
    """

    letter: str
    rotary: bool
    work_side: bool
    direction: np.ndarray
    point: np.ndarray
    travel: tuple[float, float] | None = None
    #: for tests only (never read from a description): take this axis through the inclined path even where it lies
    #: along a frame axis, its location errors then named and signed by :func:`inclined_basis`
    force_inclined: bool = False

    @property
    def frame_axis(self) -> int:
        """Index (0, 1, 2) of the frame axis the axis lies along (an inclined axis: the one nearest it)."""
        return int(np.argmax(np.abs(self.direction)))

    @property
    def inclined(self) -> bool:
        """Whether the axis is taken through the inclined path: its direction not along a frame axis, or forced."""
        return self.force_inclined or not along_frame(self.direction)

    @property
    def basis(self) -> tuple[np.ndarray, np.ndarray]:
        """``(u, v)`` (3,) each: the axis' own basis across its direction (:func:`inclined_basis`)."""
        return inclined_basis(self.direction)

    @property
    def sign(self) -> float:
        """+1 or −1: the axis' direction along its frame axis."""
        return float(np.sign(self.direction[self.frame_axis]))

    @property
    def token(self) -> str:
        return self.letter + ("'" if self.work_side else "")


@dataclass(frozen=True)
class Spindle:
    """The spindle: ``direction`` (3,) from the nose to the tool tip at the home pose, ``point`` (3,) mm, where
    the programmed tool length is measured from; ``carrier`` the letter of the axis carrying it (``"b"``: the
    bed, every axis moving the workpiece)."""

    direction: np.ndarray
    point: np.ndarray
    carrier: str

    @property
    def frame_axis(self) -> int:
        return int(np.argmax(np.abs(self.direction)))


@dataclass(frozen=True)
class MachineDescription:
    """A machine: its chains from the bed outwards, spindle, deviation selection and squareness form.

    ``deviations``: the selected deviation names (None: the default set of :mod:`.deviations`);
    ``builtin``: the built-in type it is (``"integrex-i200"``), else ``""``;
    ``aliases``: ``(ISO symbol, name)`` pairs, the names its plug-ins give deviations instead of their symbols (the
    thesis plug-in: its 13 names, ``dx_CZ`` for ``E_X0C``, ...); ``plugins``: the names of its plug-ins
    (:mod:`.plugins`: what is particular to it, SPEC §20).
    """

    name: str
    configuration: str
    tool_chain: tuple[Axis, ...]
    work_chain: tuple[Axis, ...]
    spindle: Spindle
    deviations: tuple[str, ...] | None = None
    squareness: str = "motion"
    builtin: str = ""
    aliases: tuple[tuple[str, str], ...] = ()
    plugins: tuple[str, ...] = ()

    @property
    def axes(self) -> dict[str, Axis]:
        """Every axis by letter."""
        return {a.letter: a for a in self.work_chain + self.tool_chain}

    @property
    def rotary_axes(self) -> tuple[Axis, ...]:
        """The rotary axes, work side first (bed outwards), then tool side (bed outwards)."""
        return tuple(a for a in self.work_chain + self.tool_chain if a.rotary)

    def name_of(self, symbol: str) -> str:
        """The name of the deviation with ISO 230-7 ``symbol`` on this machine: its alias, else the symbol."""
        return dict(self.aliases).get(symbol, symbol)


_TOKEN = re.compile(r"\([^)]*\)?|[A-Za-z]'?|.")


def parse_configuration(text: str, fail: Fail, key: str = "machine.configuration") -> tuple[list[str], list[str]]:
    """``(work side, tool side)`` tokens of a configuration string, each listed from the bed outwards, e.g.
    ``"w-C'bZYXB(C1)-t"`` -> ``(["C"], ["Z", "Y", "X", "B", "C1"])``; ``fail(key, message)`` on what does not parse."""
    s = text.strip()
    if not (s.startswith("w-") and s.endswith("-t")) or len(s) < 5:
        fail(key, f"{text!r} does not parse: expected the chain from workpiece to tool, 'w-<axes>b<axes>(C1)-t', "
                  "e.g. \"w-C'bZYXB(C1)-t\"")
    tokens = _TOKEN.findall(s[2:-2])
    if tokens.count("b") != 1:
        fail(key, f"{text!r}: the bed 'b' must appear once, between the workpiece-side and the tool-side axes")
    bed = tokens.index("b")
    work, tool = tokens[:bed], tokens[bed + 1:]
    seen: set[str] = set()
    for i, t in enumerate(tokens):
        if t == "b":
            continue
        if t == "(C1)":
            if i != len(tokens) - 1 or i < bed:
                fail(key, f"{text!r}: the spindle (C1) must be last, next to the tool")
            continue
        if t.startswith("("):
            fail(key, f"{text!r}: unknown spindle {t!r} (the spindle, without angle control, is (C1))")
        letter = t[0]
        if letter not in LINEAR + ROTARY:
            fail(key, f"{text!r}: unknown axis letter {t!r} (expected X, Y, Z, A, B or C, primed on the workpiece "
                      "side)")
        if letter in seen:
            fail(key, f"{text!r}: axis {letter} appears twice")
        seen.add(letter)
        primed = t.endswith("'")
        if primed and i > bed:
            fail(key, f"{text!r}: {t} is primed (moves the workpiece) but stands on the tool side of the bed 'b'")
        if not primed and i < bed:
            fail(key, f"{text!r}: {t} stands on the workpiece side of the bed 'b' but is not primed ({t}')")
    missing = [a for a in LINEAR if a not in seen]
    if missing:
        fail(key, f"{text!r}: no {', '.join(missing)} axis: the model needs the three linear axes X, Y, Z")
    if not any(a in seen for a in ROTARY):
        fail(key, f"{text!r}: no rotary axis: nothing for the ball bar or the probe to calibrate")
    if "(C1)" not in tool:
        fail(key, f"{text!r}: no spindle: end the chain with (C1) before -t")
    work_letters = [t[0] for t in reversed(work)]  # bed outwards
    tool_letters = [t[0] if t != "(C1)" else SPINDLE for t in tool]
    for side in (work_letters, [t for t in tool_letters if t != SPINDLE]):
        for lower, upper in zip(side, side[1:]):
            if lower in ROTARY and upper in LINEAR:
                fail(key, f"{text!r}: linear axis {upper} is carried by rotary axis {lower}; the model supports "
                          "linear axes between the bed and the rotary axes only")
    return work_letters, tool_letters


#: how far from unit length a direction vector may be and still be taken as meant to be one (then normalised)
UNIT_TOLERANCE = 1e-6
#: largest off-axis component, after normalising, of a direction that lies along a frame axis
ALONG_TOLERANCE = 1e-9
#: how nearly two frame axes must tie for the basis rule's order (X before Y before Z) to decide between them
TIE_TOLERANCE = 1e-12


def along_frame(direction: np.ndarray) -> bool:
    """Whether a (3,) unit vector is exactly a signed frame axis (as :func:`parse_direction` snaps one)."""
    return int(np.count_nonzero(direction)) == 1


def inclined_basis(k: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The basis across an axis of direction ``k`` (3,) unit (SPEC §21): ``u`` the unit projection onto the plane
    ⊥ k of the frame axis eᵢ with the smallest |eᵢ·k| (ties within :data:`TIE_TOLERANCE`: X before Y before Z),
    ``v = k × u``.  For +Y: u = +X, v = −Z."""
    k = np.asarray(k, dtype=float)
    a = np.abs(k)
    i = int(np.flatnonzero(a <= a.min() + TIE_TOLERANCE)[0])
    u = np.eye(3)[i] - k[i] * k
    u = u / np.linalg.norm(u)
    return u, np.cross(k, u)


def parse_direction(value, fail: Fail, key: str) -> np.ndarray:
    """A direction: ``"+Y"``/``"-Z"`` or a 3-vector within :data:`UNIT_TOLERANCE` of unit length -> (3,) unit vector
    (normalised; snapped onto the frame axis it lies along when its off-axis parts are ≤ :data:`ALONG_TOLERANCE`
    after normalising, else kept: an inclined axis, SPEC §21).  A zero vector and one further from unit length each
    fail with their own reason."""
    if isinstance(value, str):
        m = re.fullmatch(r"\s*([+-]?)([XYZ])\s*", value.upper())
        if not m:
            fail(key, f"{value!r} is not a direction (expected \"+X\", \"-Y\", ... or a unit vector [x, y, z])")
        v = np.zeros(3)
        v[FRAME.index(m.group(2))] = -1.0 if m.group(1) == "-" else 1.0
        return v
    v = vector3(value, fail, key)
    norm = float(np.linalg.norm(v))
    if norm == 0.0:
        fail(key, "a zero vector has no direction")
    if abs(norm - 1.0) > UNIT_TOLERANCE:
        fail(key, f"{_shown(v)} is not a unit vector (its length is {norm:.9g}): a direction is accepted within "
                  f"{UNIT_TOLERANCE:g} of unit length")
    u = v / norm
    i = int(np.argmax(np.abs(u)))
    if np.delete(np.abs(u), i).max() > ALONG_TOLERANCE:
        return u
    out = np.zeros(3)
    out[i] = np.sign(u[i])
    return out


def vector3(value, fail: Fail, key: str) -> np.ndarray:
    """Three finite numbers -> (3,) array."""
    if not isinstance(value, (list, tuple)) or len(value) != 3 or \
            not all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value):
        fail(key, f"expected three numbers [x, y, z], got {value!r}")
    v = np.asarray(value, dtype=float)
    if not np.isfinite(v).all():
        fail(key, f"{_shown(v)} is not finite")
    return v


def _shown(v) -> str:
    """A vector as the user wrote it: ``[0, 0.6, 0.8]`` (not numpy's ``np.float64(...)`` reprs)."""
    return "[" + ", ".join(f"{float(x):g}" for x in v) + "]"


def on_one_line(a: Axis, b: Axis) -> bool:
    """Whether two rotary axes share one line (parallel, and each one's point on the other's line)."""
    if abs(abs(float(a.direction @ b.direction)) - 1.0) > 1e-12:
        return False
    d = b.point - a.point
    return float(np.linalg.norm(d - (d @ a.direction) * a.direction)) < 1e-9


def check_geometry(desc: MachineDescription, fail: Fail, key: str = "machine") -> None:
    """The rules a description's geometry obeys, beyond each value's own: no two rotary axes of one side on one
    line (their location errors could not be told apart), and a spindle that the axis carrying it moves."""
    for side in (desc.work_chain, desc.tool_chain):
        rot = [a for a in side if a.rotary]
        for i, a in enumerate(rot):
            for b in rot[i + 1:]:
                if on_one_line(a, b):
                    fail(f"{key}.axes.{b.letter}", f"axes {a.letter} and {b.letter} turn about one line: their "
                         "position and orientation errors cannot be told apart; describe them on different lines")
    carrier = desc.axes.get(desc.spindle.carrier)
    if carrier is not None and carrier.rotary:
        s = desc.spindle
        along = abs(abs(float(s.direction @ carrier.direction)) - 1.0) < 1e-12
        d = s.point - carrier.point
        on_line = float(np.linalg.norm(d - (d @ carrier.direction) * carrier.direction)) < 1e-9
        if along and on_line:
            fail(f"{key}.spindle.direction", f"the spindle lies along the {carrier.letter} axis that carries it, on "
                 f"its line: turning {carrier.letter} does not move the tool point, so nothing of {carrier.letter} "
                 "can be measured with it")
