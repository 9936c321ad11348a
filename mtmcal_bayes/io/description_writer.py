"""Writing a described machine's campaign (SPEC §19, docs/machines.md): its description and its measurements."""

from __future__ import annotations

import numpy as np

from .. import units
from ..campaign import Campaign
from ..machines.description import FRAME, MachineDescription
from ..machines.deviations import quantities as deviation_table
from ..parameters import quantity_unit
from .design_table import design_to_dict
from .probe_readings import readings_entry
from .truth_table import truth_to_dict


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


def described_to_dict(c: Campaign, doc: dict, save_dir=None) -> dict:
    """``doc`` (format, date, ...) completed with a described campaign's machine, ball bar, probe, priors and truth
    (``save_dir``: where it is saved, which the probe runs' DPRNT files are named relative to)."""
    um = lambda v: units.from_internal(v, "um")  # noqa: E731
    m = c.machine
    machine = {"name": m.name} if m.name else {}
    machine.update({k: v for k, v in (("serial", m.serial), ("type", m.type)) if v})
    machine.update(description_to_dict(m.description))
    doc["machine"] = machine
    bb = c.ballbar
    if bb.runs or bb.setups:
        b: dict = {"instrument": bb.instrument} if bb.instrument else {}
        b.update({"length_mm": bb.length, "accuracy_um": um(bb.accuracy)})
        if bb.feed_mm_per_min is not None:
            b["feed_mm_per_min"] = bb.feed_mm_per_min
        if bb.convention != "thesis":
            b["convention"] = bb.convention
        b["setups"] = {s.id: {"R_B_mm": s.R_B} for s in bb.setups.values()}
        b["mounts"] = {mt.id: {"position_mm": [float(x) for x in mt.position]} for mt in bb.mounts.values()}
        b["runs"] = []
        for run in bb.runs:
            d = {"pattern": run.pattern, "setup": run.setup, "mount": run.mount, **_arc_hold(run),
                 **({"reversed": True} if run.reversed else {}),
                 **({"convention": run.convention} if run.convention else {})}
            d.update({f"{k}_um": [um(x) for x in v] for k, v in run.repeats.items()})
            b["runs"].append(d)
        for run in bb.planned:  # after the measured runs, in measuring order
            d = {"pattern": run.pattern, "setup": run.setup, "mount": run.mount, **_arc_hold(run),
                 **({"reversed": True} if run.reversed else {}),
                 **({"convention": run.convention} if run.convention else {}), "planned": True,
                 "repeats": int(run.repeats)}
            d.update({k: v for k, v in (("minutes", run.minutes), ("order", run.order), ("why", run.why)) if v})
            b["runs"].append(d)
        if not b["runs"]:
            del b["runs"]  # a machine with set-ups and mounts only
        doc["ballbar"] = b
    p = c.probe
    if p is not None:
        pd: dict = {"instrument": p.instrument} if p.instrument else {}
        if p.repeatability is not None:
            pd["repeatability_um"] = um(p.repeatability)
        pd["styli"] = {sid: {"length_mm": float(length)} for sid, length in p.styli.items()}
        pd["runs"] = [{"id": r.id, "stylus": r.stylus, "sphere_mm": [float(x) for x in r.sphere],
                       "angles_deg": {k: [float(x) for x in units.from_internal(v, "deg")] for k, v in r.angles.items()},
                       **readings_entry(r, c.base_dir, save_dir)} for r in p.runs]
        doc["probe"] = pd
    if c.priors:
        doc["priors"] = {}
        for name, spec in c.priors.items():
            unit = quantity_unit(name)
            doc["priors"][name] = {"dist": spec["dist"], **{f"{k}_{unit}": units.from_internal(v, unit)
                                                            for k, v in spec.items() if k != "dist"}}
    if c.truth is not None:
        doc["truth"] = truth_to_dict(c.truth)
    if c.design is not None:
        doc["design"] = design_to_dict(c.design, quantities=deviation_table(m.description))
    return doc


def _arc_hold(run) -> dict:
    """``arc_deg``, ``step_deg`` and ``hold_deg`` of a run (measured or planned)."""
    d: dict = {}
    if run.arc_deg is not None:
        arc = np.asarray(run.arc_deg, dtype=float)
        d["arc_deg"] = [float(arc[0]), float(arc[-1])]
        d["step_deg"] = float(arc[1] - arc[0])
    if run.hold_deg:
        d["hold_deg"] = {k: float(v) for k, v in run.hold_deg.items()}
    return d
