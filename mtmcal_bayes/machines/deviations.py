"""The location errors of a described machine, generated with their ISO 230-7 symbols (SPEC §19, §21).

Per rotary axis K along frame axis k: the position of its axis line along the two frame axes perpendicular
to k, at its ``point_mm`` (µm: ``E_X0C``, ``E_Y0C``), its orientation about those two axes (″: ``E_A0C``,
``E_B0C``) and its zero position (″: ``E_C0C``).  For a spindle carried by a rotary axis K: its position and
orientation relative to K (``E_X(0C1)B``, ``E_A(0C1)B``) and its offset along its own axis, named by the frame
axis it lies along at the home pose (``E_Z(0C1)B``, signed along +Z: positive shortens a tool pointing −Z).
The three squareness errors of the linear axes (ISO 230-1): ``E_C0X`` (X to Y), ``E_B0X`` (X to Z), ``E_A0Y``
(Y to Z).

An inclined rotary axis K (direction k not along a frame axis, SPEC §21) has its own basis u, v
(:func:`~.description.inclined_basis`): positions along u and v (µm: ``E_U0K``, ``E_V0K``), orientations about them
(″: ``E_RU0K``, ``E_RV0K``) and its zero, about k (″: ``E_K0K``).  A spindle carried by a rotary axis has the basis
u = the unit projection of k across the spindle direction s, v = s × u; where both lie along frame axes its errors
keep the frame names above, else ``E_U(0C1)K``, ``E_V(0C1)K``, ``E_RU(0C1)K``, ``E_RV(0C1)K`` and ``E_W(0C1)K``
(its offset along itself, signed along +s).

Each is a small rigid displacement of the body the axis carries, applied at the home pose and carried along
by the axes below it (:mod:`mtmcal_bayes.machines.chain`); an orientation error turns about the axis'
``point_mm`` (the spindle's about the spindle's ``point_mm``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..parameters import Quantity
from .description import ALONG_TOLERANCE, FRAME, ROTARY_ABOUT, SPINDLE, MachineDescription, inclined_basis

#: squareness errors: symbol -> (frame axis it turns about, the linear axis it tilts, the reference axis)
SQUARENESS_ERRORS: dict[str, tuple[int, str, str]] = {
    "E_C0X": (2, "X", "Y"), "E_B0X": (1, "X", "Z"), "E_A0Y": (0, "Y", "Z"),
}


@dataclass(frozen=True)
class Deviation:
    """One location error: ``name`` in parameter vectors (the ISO symbol, or the thesis name on the thesis
    machine), ``body`` the axis letter whose carried body it displaces (``"C1"``: the spindle; a squareness:
    the linear axis it tilts), ``role`` ``"position"``, ``"orientation"`` or ``"squareness"``, ``component``
    the frame axis (0, 1, 2) it lies along or turns about (None: an inclined axis' or spindle's own basis vector),
    ``direction`` the unit vector (3 floats, machine frame, home pose) it lies along or turns about right-handedly
    (for a frame-named error: that frame axis' unit vector)."""

    name: str
    symbol: str
    kind: str
    body: str
    role: str
    component: int | None
    meaning: str
    direction: tuple[float, float, float] = (0.0, 0.0, 0.0)

    @property
    def quantity(self) -> Quantity:
        return Quantity(self.name, self.kind, self.meaning)

    @property
    def vector(self) -> np.ndarray:
        """:attr:`direction` as a (3,) array."""
        return np.array(self.direction, dtype=float)


#: one generated error before it is named: (symbol, kind, body, role, frame component or None, direction, meaning)
_Row = tuple[str, str, str, str, "int | None", tuple, str]


def _unit(i: int) -> tuple[float, float, float]:
    return tuple(float(x) for x in np.eye(3)[i])


def _frame_index(vec: np.ndarray) -> int | None:
    """The frame axis a unit vector lies along with a + or − sign (off-axis parts ≤ 1e-9), else None."""
    i = int(np.argmax(np.abs(vec)))
    return i if np.delete(np.abs(vec), i).max() <= ALONG_TOLERANCE else None


def _perpendicular(k: int) -> list[int]:
    return [i for i in range(3) if i != k]


def _across(tail: str, body: str, k: int, *, line: str, axis: str, relative: str = "") -> list[_Row]:
    """The four errors of a line along frame axis ``k`` across it: its position along, then its orientation about,
    the two perpendicular frame axes (symbols ``E_<letter><tail>``; meanings "position of <line> along X<relative>",
    "orientation of <axis> about X<relative>")."""
    return ([(f"E_{FRAME[i]}{tail}", "length", body, "position", i, _unit(i),
              f"position of {line} along {FRAME[i]}{relative}") for i in _perpendicular(k)] +
            [(f"E_{ROTARY_ABOUT[FRAME[i]]}{tail}", "angle", body, "orientation", i, _unit(i),
              f"orientation of {axis} about {FRAME[i]}{relative}") for i in _perpendicular(k)])


def _across_basis(tail: str, body: str, u: np.ndarray, v: np.ndarray, *, line: str, axis: str, relative: str = ""
                  ) -> list[_Row]:
    """The four errors of a line across it in its own basis ``u``, ``v`` (3,) each (SPEC §21): positions along u, v
    (``E_U<tail>``, ``E_V<tail>``), then orientations about them (``E_RU<tail>``, ``E_RV<tail>``)."""
    shown = {"U": _shown(u), "V": _shown(v)}
    vec = {"U": tuple(float(x) for x in u), "V": tuple(float(x) for x in v)}
    return ([(f"E_{b}{tail}", "length", body, "position", None, vec[b],
              f"position of {line} along {b} = {shown[b]}{relative}") for b in "UV"] +
            [(f"E_R{b}{tail}", "angle", body, "orientation", None, vec[b],
              f"orientation of {axis} about {b} = {shown[b]}{relative}") for b in "UV"])


def _shown(v: np.ndarray) -> str:
    return "[" + ", ".join(f"{float(x):.6g}" for x in v + 0.0) + "]"


def spindle_basis(desc: MachineDescription) -> tuple[np.ndarray, np.ndarray] | None:
    """``(u, v)`` (3,) each: the basis of the spindle relative to the rotary axis carrying it (SPEC §21): u the unit
    projection of that axis' direction k onto the plane ⊥ s (s the spindle's direction), v = s × u; where k lies
    along s (the spindle parallel to its axis, off its line) u is the basis rule's for s.  None: no rotary axis
    carries the spindle."""
    carrier = desc.axes.get(desc.spindle.carrier)
    if carrier is None or not carrier.rotary:
        return None
    s, k = desc.spindle.direction, carrier.direction
    u = k - (k @ s) * s
    norm = float(np.linalg.norm(u))
    if norm < 1e-9:
        return inclined_basis(s)
    u = u / norm
    return u, np.cross(s, u)


def spindle_own_basis(desc: MachineDescription) -> bool:
    """Whether the spindle's errors are named in its own basis (:func:`spindle_basis` not along frame axes)."""
    basis = spindle_basis(desc)
    return basis is not None and (_frame_index(basis[0]) is None or _frame_index(basis[1]) is None)


def _rotary(desc: MachineDescription) -> list[_Row]:
    """The location errors of every rotary axis, work side first (bed outwards), then tool side."""
    out: list[_Row] = []
    for ax in desc.rotary_axes:
        K = ax.letter
        if ax.inclined:
            u, v = ax.basis
            out += _across_basis(f"0{K}", K, u, v, line=f"the {K} axis line", axis=f"the {K} axis")
            out.append((f"E_{K}0{K}", "angle", K, "orientation", None, tuple(float(x) for x in ax.direction),
                        f"zero position of the {K} axis (about its direction {_shown(ax.direction)})"))
            continue
        k = ax.frame_axis
        out += _across(f"0{K}", K, k, line=f"the {K} axis line", axis=f"the {K} axis")
        out.append((f"E_{ROTARY_ABOUT[FRAME[k]]}0{K}", "angle", K, "orientation", k, _unit(k),
                    f"zero position of the {K} axis"))
    return out


def _spindle(desc: MachineDescription) -> list[_Row]:
    """The spindle's location errors relative to the rotary axis carrying it (none if no rotary axis does)."""
    basis = spindle_basis(desc)
    if basis is None:
        return []
    K, tail = desc.spindle.carrier, f"(0{SPINDLE}){desc.spindle.carrier}"
    u, v = basis
    words = dict(line="the spindle axis", axis="the spindle axis", relative=f" relative to the {K} axis")
    if not spindle_own_basis(desc):  # §19's frame names, signed along +X, +Y, +Z
        s = desc.spindle.frame_axis
        return _across(tail, SPINDLE, s, **words) + [
            (f"E_{FRAME[s]}{tail}", "length", SPINDLE, "position", s, _unit(s),
             f"offset of the spindle along its own axis ({FRAME[s]}), signed along +{FRAME[s]}")]
    s = desc.spindle.direction
    return _across_basis(tail, SPINDLE, u, v, **words) + [
        (f"E_W{tail}", "length", SPINDLE, "position", None, tuple(float(x) for x in s),
         f"offset of the spindle along its own axis, signed along its direction {_shown(s)}")]


def generated(desc: MachineDescription) -> list[Deviation]:
    """Every location error the description has, in chain order (work side, tool side, spindle, squareness)."""
    out = _rotary(desc) + _spindle(desc)
    for sym, (about, tilted, ref) in SQUARENESS_ERRORS.items():
        out.append((sym, "angle", tilted, "squareness", about, _unit(about), f"squareness of {tilted} to {ref}"))
    return [Deviation(desc.name_of(sym), sym, kind, body, role, comp, meaning, direction)
            for sym, kind, body, role, comp, direction, meaning in out]


def quantities(desc: MachineDescription) -> dict[str, Quantity]:
    """Every generated deviation of the machine as a :class:`~mtmcal_bayes.parameters.Quantity`, by name."""
    return {d.name: d.quantity for d in generated(desc)}
