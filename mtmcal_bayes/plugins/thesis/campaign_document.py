"""The thesis' campaign keys written: a campaign in the thesis' format as the TOML document it reads back
(:mod:`.campaign_keys`); the engine writes the format line and the date (:mod:`mtmcal_bayes.io.campaign_writer`)
and asks the machine for the rest (its ``campaign_document``)."""

from __future__ import annotations

from pathlib import Path

from ... import units
from ...campaign import Campaign, PlannedRun, Probe
from ...io.design_table import design_to_dict
from ...io.probe_readings import readings_entry, relative_file
from ...io.tomlio import Fixed
from ...io.truth_table import truth_to_dict
from ...parameters import DEVIATIONS, QUANTITIES

def campaign_document(c: Campaign, doc: dict, save_dir: Path | None = None) -> dict:
    """The rest of ``doc`` (format, date, ...) for a campaign in the thesis' format: its machine, ball bar, probe,
    published values, priors, tolerances, truth and design (``save_dir``: where trace and DPRNT files are written
    relative to; absolute when ``None``)."""
    um = lambda v: units.from_internal(v, "um")  # noqa: E731
    doc["machine"] = {"name": c.machine.name, "configuration": c.machine.configuration,
                      **({"serial": c.machine.serial} if c.machine.serial else {}),
                      **({"type": c.machine.type} if c.machine.type else {}),
                      **{f"travel_{a}_mm": v for a, v in c.machine.travel.items()}}
    bb = c.ballbar
    b: dict = {}
    if bb.instrument:
        b["instrument"] = bb.instrument
    b["length_mm"] = bb.length
    b["accuracy_um"] = um(bb.accuracy)
    if bb.feed_mm_per_min is not None:
        b["feed_mm_per_min"] = bb.feed_mm_per_min
    if bb.cr_geometry != "RC-LB":
        b["cr_geometry"] = bb.cr_geometry
    b["convention"] = bb.convention
    if bb.alternative_reason and bb.reading_choices():  # the reason of a choice whose runs are still there
        b["alternative_reason"] = bb.alternative_reason
    b["setups"] = {s.id: {"R_B_mm": s.R_B, "Z_T_mm": s.Z_T, "X_T_mm": s.X_T} for s in bb.setups.values()}
    b["mounts"] = {m.id: {"Z_C_mm": m.Z_C, "R_C_mm": m.R_C} for m in bb.mounts.values()}
    b["runs"] = []
    for run in bb.runs:
        d = {"pattern": run.pattern, "setup": run.setup, "mount": run.mount}
        if run.convention:
            d["convention"] = run.convention
        if run.alternative_convention:
            d["alternative_convention"] = run.alternative_convention
        if run.trace_csv:
            d["trace_csv"] = [_relative(c, f, save_dir) for f in run.trace_csv]
        else:
            d.update({f"{k}_um": [um(x) for x in v] for k, v in run.repeats.items()})
        b["runs"].append(d)
    b["runs"] += [planned_run_dict(run) for run in bb.planned]  # after the measured runs, in measuring order
    if not b["runs"]:
        del b["runs"]  # a machine with set-ups and mounts only
    doc["ballbar"] = b
    if c.probe is not None:
        doc["probe"] = _probe_dict(c.probe, c, save_dir)
    if c.reported:
        doc["reported"] = {m: {f"{n}_{v.unit}": Fixed(units.from_internal(v.value, v.unit), v.decimals)
                               for n, v in vals.items()} for m, vals in c.reported.items()}
    if c.priors:
        doc["priors"] = {}
        for name, spec in c.priors.items():
            unit = DEVIATIONS[name].unit if name in DEVIATIONS else "um"  # nuisance terms are lengths
            doc["priors"][name] = {"dist": spec["dist"], **{f"{k}_{unit}": units.from_internal(v, unit)
                                                            for k, v in spec.items() if k != "dist"}}
    if c.tolerances:
        doc["tolerances"] = {}
        for name, t in c.tolerances.items():
            unit = QUANTITIES[name].unit
            ends = {k: units.from_internal(v, unit) for k, v in (("low", t.low), ("high", t.high)) if v is not None}
            symmetric = t.low is not None and t.high is not None and t.low == -t.high
            doc["tolerances"][f"{name}_{unit}"] = ends["high"] if symmetric else ends
    if c.truth is not None:
        doc["truth"] = truth_to_dict(c.truth)
    if c.design is not None:
        doc["design"] = design_to_dict(c.design)
    return doc


def planned_run_dict(run: PlannedRun) -> dict:
    """The ``[[ballbar.runs]]`` table of a planned run: ``planned = true``, ``repeats`` and what else is set."""
    d: dict = {"pattern": run.pattern, "setup": run.setup, "mount": run.mount, "planned": True,
               "repeats": int(run.repeats)}
    if run.convention:
        d["convention"] = run.convention
    if run.length is not None:
        d["length_mm"] = run.length
    if run.minutes is not None:
        d["minutes"] = run.minutes
    if run.order is not None:
        d["order"] = int(run.order)
    if run.why:
        d["why"] = run.why
    return d


def _probe_dict(p: Probe, c: Campaign, save_dir: Path | None) -> dict:
    d: dict = {}
    if p.instrument:
        d["instrument"] = p.instrument
    if p.repeatability is not None:
        d["repeatability_um"] = units.from_internal(p.repeatability, "um")

    def readings(run) -> dict:  # DPRNT files relative to the saved file, else the centres
        return readings_entry(run, c.base_dir, save_dir)

    if p.b_axis is not None:
        b = p.b_axis
        styli = {}
        for s in b.styli.values():
            sd = {"R_B_mm": s.R_B}
            if s.ball_radius:
                sd["ball_radius_mm"] = s.ball_radius
            if s.nominal is not None:
                sd["nominal_mm"] = s.nominal
            styli[s.id] = {**sd, **readings(s)}
        d["b_axis"] = {"X_T_mm": b.X_T, **({"Z_C_mm": b.Z_C} if b.Z_C is not None else {}),
                       "angles_deg": b.angles_deg, "styli": styli}
    if p.c_axis is not None:
        x = p.c_axis
        cd = {"R_C_mm": x.R_C, "Z_C_mm": x.Z_C, "axis_xy_mm": x.axis_xy, "angles_deg": x.angles_deg}
        if x.stylus:
            cd["stylus"] = x.stylus
        if x.R_B is not None:
            cd["R_B_mm"] = x.R_B
        if x.ball_radius:
            cd["ball_radius_mm"] = x.ball_radius
        if x.datum != "machine":
            cd["datum"] = x.datum
        d["c_axis"] = {**cd, **readings(x)}
    return d


def _relative(c: Campaign, name: str, save_dir: Path | None) -> str:
    """A file named in ``c`` (relative to its folder), as seen from ``save_dir`` (absolute when ``None``)."""
    return relative_file(c.base_dir, name, save_dir)