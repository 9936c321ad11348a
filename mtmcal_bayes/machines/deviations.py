"""The location errors of a described machine, generated with their ISO 230-7 symbols (SPEC §19).

Per rotary axis K along frame axis k: the position of its axis line along the two frame axes perpendicular
to k, at its ``point_mm`` (µm: ``E_X0C``, ``E_Y0C``), its orientation about those two axes (″: ``E_A0C``,
``E_B0C``) and its zero position (″: ``E_C0C``).  For a spindle carried by a rotary axis K: its position and
orientation relative to K (``E_X(0C1)B``, ``E_A(0C1)B``) and its offset along its own axis, named by the frame
axis it lies along at the home pose (``E_Z(0C1)B``, signed along +Z: positive shortens a tool pointing −Z).
The three squareness errors of the linear axes (ISO 230-1): ``E_C0X`` (X to Y), ``E_B0X`` (X to Z), ``E_A0Y``
(Y to Z).

Each is a small rigid displacement of the body the axis carries, applied at the home pose and carried along
by the axes below it (:mod:`mtmcal_bayes.models.chain`); an orientation error turns about the axis'
``point_mm`` (the spindle's about the spindle's ``point_mm``).
"""

from __future__ import annotations

from dataclasses import dataclass

from ..parameters import Quantity
from .description import FRAME, ROTARY_ABOUT, SPINDLE, MachineDescription

#: squareness errors: symbol -> (frame axis it turns about, the linear axis it tilts, the reference axis)
SQUARENESS_ERRORS: dict[str, tuple[int, str, str]] = {
    "E_C0X": (2, "X", "Y"), "E_B0X": (1, "X", "Z"), "E_A0Y": (0, "Y", "Z"),
}


@dataclass(frozen=True)
class Deviation:
    """One location error: ``name`` in parameter vectors (the ISO symbol, or the thesis name on the thesis
    machine), ``body`` the axis letter whose carried body it displaces (``"C1"``: the spindle; a squareness:
    the linear axis it tilts), ``role`` ``"position"``, ``"orientation"`` or ``"squareness"``, ``component``
    the frame axis (0, 1, 2) it lies along or turns about."""

    name: str
    symbol: str
    kind: str
    body: str
    role: str
    component: int
    meaning: str

    @property
    def quantity(self) -> Quantity:
        return Quantity(self.name, self.kind, self.meaning)


def _perpendicular(k: int) -> list[int]:
    return [i for i in range(3) if i != k]


def _across(tail: str, body: str, k: int, *, line: str, axis: str, relative: str = ""
            ) -> list[tuple[str, str, str, str, int, str]]:
    """The four errors of a line along frame axis ``k`` across it: its position along, then its orientation about,
    the two perpendicular frame axes (symbols ``E_<letter><tail>``; meanings "position of <line> along X<relative>",
    "orientation of <axis> about X<relative>")."""
    return ([(f"E_{FRAME[i]}{tail}", "length", body, "position", i, f"position of {line} along {FRAME[i]}{relative}")
             for i in _perpendicular(k)] +
            [(f"E_{ROTARY_ABOUT[FRAME[i]]}{tail}", "angle", body, "orientation", i,
              f"orientation of {axis} about {FRAME[i]}{relative}") for i in _perpendicular(k)])


def generated(desc: MachineDescription) -> list[Deviation]:
    """Every location error the description has, in chain order (work side, tool side, spindle, squareness)."""
    out: list[tuple[str, str, str, str, int, str]] = []
    for ax in desc.rotary_axes:
        K, k = ax.letter, ax.frame_axis
        out += _across(f"0{K}", K, k, line=f"the {K} axis line", axis=f"the {K} axis")
        out.append((f"E_{ROTARY_ABOUT[FRAME[k]]}0{K}", "angle", K, "orientation", k,
                    f"zero position of the {K} axis"))
    carrier = desc.axes.get(desc.spindle.carrier)
    if carrier is not None and carrier.rotary:
        K, s = carrier.letter, desc.spindle.frame_axis
        out += _across(f"(0{SPINDLE}){K}", SPINDLE, s, line="the spindle axis", axis="the spindle axis",
                       relative=f" relative to the {K} axis")
        out.append((f"E_{FRAME[s]}(0{SPINDLE}){K}", "length", SPINDLE, "position", s,
                    f"offset of the spindle along its own axis ({FRAME[s]}), signed along +{FRAME[s]}"))
    for sym, (about, tilted, ref) in SQUARENESS_ERRORS.items():
        out.append((sym, "angle", tilted, "squareness", about, f"squareness of {tilted} to {ref}"))
    return [Deviation(desc.name_of(sym), sym, kind, body, role, comp, meaning)
            for sym, kind, body, role, comp, meaning in out]


def redundant(desc: MachineDescription) -> dict[str, str]:
    """Generated errors left out of the default set, with why: the spindle's orientation about the axis carrying
    it (that axis' zero position), its position along that axis (the tool ball's own offset, each setup's
    nuisance term) and the squareness of the linear axes (held at zero, as in the thesis: measured by other means)."""
    why: dict[str, str] = {}
    carrier = desc.axes.get(desc.spindle.carrier)
    for d in generated(desc):
        if d.role == "squareness":
            why[d.name] = "linear-axis squareness: measured by other means; held at zero unless selected"
        elif d.body == SPINDLE and carrier is not None and d.component == carrier.frame_axis:
            why[d.name] = (f"the same as the {carrier.letter} axis' zero position" if d.role == "orientation" else
                           "the same as the tool ball's own offset (each setup's nuisance term)")
    return why


def selected(desc: MachineDescription) -> list[Deviation]:
    """The deviations a campaign on this machine estimates: ``[machine] deviations`` if given, else the generated
    ones less :func:`redundant` (on the thesis machine: the thesis' sampled ten, Table 2.1 less the squareness)."""
    every = generated(desc)
    if desc.deviations is not None:
        chosen = set(desc.deviations)
        return [d for d in every if d.name in chosen or d.symbol in chosen]
    skip = redundant(desc)
    return [d for d in every if d.name not in skip]


def quantities(desc: MachineDescription) -> dict[str, Quantity]:
    """Every generated deviation of the machine as a :class:`~mtmcal_bayes.parameters.Quantity`, by name."""
    return {d.name: d.quantity for d in generated(desc)}
