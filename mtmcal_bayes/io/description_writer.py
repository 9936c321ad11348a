"""Writing a machine's description (SPEC §19, docs/machines.md) and the engine's ``[machine]`` table of a campaign."""

from __future__ import annotations

import numpy as np

from .. import units
from ..campaign import Machine
from ..machines.description import FRAME, MachineDescription
from .machine_reader import description_of


def description_to_dict(desc: MachineDescription) -> dict:
    """The TOML table of a description (a built-in type is named, not written out: ``{"description": type}``)."""
    if desc.builtin:
        return {"description": desc.builtin}
    d: dict = {"configuration": desc.configuration}
    if desc.squareness != "motion":
        d["squareness"] = desc.squareness
    if desc.deviations is not None:
        d["deviations"] = list(desc.deviations)
    axes: dict = {}
    for ax in desc.work_chain + desc.tool_chain:
        if ax.rotary:
            a = {"direction": _direction(ax.direction), "point_mm": [float(x) for x in ax.point]}
            if ax.travel is not None:
                a["travel_deg"] = [float(units.from_internal(x, "deg")) for x in ax.travel]
        else:
            a = {"travel_mm": [float(x) for x in ax.travel]} if ax.travel is not None else {}
        if a:
            axes[ax.letter] = a
    d["axes"] = axes
    d["spindle"] = {"direction": _direction(desc.spindle.direction),
                    "point_mm": [float(x) for x in desc.spindle.point]}
    return d


def _direction(v: np.ndarray) -> str:
    i = int(np.argmax(np.abs(v)))
    return ("+" if v[i] > 0 else "-") + FRAME[i]


def machine_table(m: Machine) -> dict:
    """``[machine]`` of a campaign: its name, serial, type and axis travels, and its description (named where it is
    a built-in type, else written out; a machine built in Python without one is the thesis machine's)."""
    desc = description_of(m)
    machine = {"name": m.name} if m.name or desc.name else {}  # no name read back as the description's
    machine.update({k: v for k, v in (("serial", m.serial), ("type", m.type)) if v})
    machine.update({f"travel_{a}_mm": v for a, v in m.travel.items()})
    machine.update(description_to_dict(desc))
    return machine
