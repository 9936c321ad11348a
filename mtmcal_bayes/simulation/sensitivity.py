"""Sensitivity of every pattern's eccentricities to every deviation and mounting offset, on any machine.

The numbers behind thesis Tables 2.4–2.6 (which show them only as plots), generalised to every machine (SPEC §19):
the Jacobian of a forward model at zero, in µm of eccentricity per ″ (angles) or per µm (lengths), for one run of
every pattern of the machine in one geometry of a campaign (:func:`table_campaign`).  What differs between machines
is asked of the machine: its patterns and their components, which mounts its campaign format lets a pattern use,
its default model, its deviations, and how its geometry is written (a plug-in may state each; the thesis': its 12
patterns in the order of Tables 2.2/2.3, B patterns only with the W ball on the C axis, its lever arms).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .. import units
from ..campaign import Campaign, Run
from ..errors import InputError
from ..io.campaign_reader import deviation_quantities
from ..io.machine_reader import description_of
from ..machines.patterns import axis_of, ball_radius, components, patterns_of
from ..machines.plugins import provided
from ..models import default_kinematic_model, jacobian_at_zero, make_model
from ..parameters import MOUNT_NUISANCE, SETUP_NUISANCE, ParameterSpace

#: below this distance, mm, a W ball lies on the line of the axis that swivels it (machines.patterns)
ON_LINE_MM = 1e-9


def _no_conflict(pattern: str, mount) -> None:
    """The engine's own rule: any mount serves any pattern (no reason against it)."""


def _placement(campaign: Campaign, pattern: str, conflict) -> tuple[str, dict | None]:
    """``(mount id, held positions)`` of the runs of ``pattern``'s axis K: those of the campaign's first run of K,
    else of its first mount (the other axes at 0), taking only a mount the campaign's format lets the pattern use
    (``conflict``) and, for a workpiece-side K, whose W ball lies off K's line (on it, K's patterns do not move the
    ball: K's tilts show only beside its position, and the R and T directions are a convention).  None: an
    :class:`InputError` naming ``ballbar.mounts``."""
    desc, bb = description_of(campaign.machine), campaign.ballbar
    ax = axis_of(desc, pattern)
    tried = [(r.mount, r.hold_deg) for r in bb.runs if r.pattern[0] == ax.letter] + [(m, None) for m in bb.mounts]
    conflicts, on_line = {}, {}
    for mount, hold in tried:
        why = conflict(pattern, bb.mounts[mount])
        if why is not None:
            conflicts.setdefault(mount, why)
            continue
        radius = ball_radius(desc, ax, bb.mounts[mount].centre(), hold) if ax.work_side else np.inf
        if radius > ON_LINE_MM:
            return mount, hold
        on_line.setdefault(mount, radius)
    need = f"the sensitivity table needs a mount for the {ax.letter} patterns"
    if ax.work_side:
        need += f" whose W ball lies off the {ax.letter} axis line (R_{ax.letter}_mm > 0, its distance from that line)"
    parts = [need, *(conflicts[m] for m in bb.mounts if m in conflicts)]
    if on_line:
        parts.append("have " + ", ".join(f"{m} R_{ax.letter}_mm = {on_line[m]:g}" for m in bb.mounts if m in on_line))
    raise InputError(campaign.source, "ballbar.mounts", "; ".join(parts))


def table_campaign(campaign: Campaign) -> Campaign:
    """A copy of ``campaign`` whose runs are one of every pattern of its machine (its plug-in's ``patterns`` where it
    states them, else ``<K><d>`` of every rotary axis), each with one zero repeat of every component, on the
    campaign's first tool setup, at the mount and held positions of :func:`_placement`, over its axis' default arc;
    no planned runs and no probe."""
    machine, bb = campaign.machine, campaign.ballbar
    desc = description_of(machine)
    if not bb.setups:
        raise InputError(campaign.source, "ballbar.setups", "the sensitivity table needs a ball-bar set-up: give "
                         "[ballbar] length_mm, a [ballbar.setups.<id>] and a [ballbar.mounts.<id>]")
    patterns = provided(machine, "patterns") or patterns_of(desc)
    comps = provided(machine, "pattern_components") or (lambda p: components(desc, p))
    conflict = provided(machine, "mount_conflict", _no_conflict)
    setup = next(iter(bb.setups))
    placed = {}
    for p in patterns:
        if p[0] not in placed:
            placed[p[0]] = _placement(campaign, p, conflict)
    out = copy.deepcopy(campaign)
    out.ballbar.runs = [Run(p, setup, placed[p[0]][0], {c: np.zeros(1) for c in comps(p)}, hold_deg=placed[p[0]][1])
                        for p in patterns]
    out.ballbar.planned, out.probe = [], None
    return out


def _geometry(c: Campaign, campaign: Campaign) -> str:
    """The engine's geometry line of the table campaign ``c`` of ``campaign``: the configuration, the set-up and the
    bar, and each axis whose patterns are not where the campaign's first run of that axis is (:func:`_placement`)."""
    bb = c.ballbar
    setup = bb.runs[0].setup
    text = (f"{description_of(c.machine).configuration}; tool setup {setup} (R_B = {bb.setups[setup].R_B:g} mm), "
            f"L_B = {bb.length:g} mm; mounts and held axes of the campaign's runs")
    first: dict[str, Run] = {}
    for run in campaign.ballbar.runs:
        first.setdefault(run.pattern[0], run)
    moved = {}
    for run in bb.runs:
        was = first.get(run.pattern[0])
        if was is None or (was.mount, was.hold_deg) != (run.mount, run.hold_deg):
            held = ", ".join(f"{a} = {v:g}°" for a, v in (run.hold_deg or {}).items())
            why = "no run of the axis" if was is None else "its first run's W ball lies on the axis line"
            moved.setdefault(run.pattern[0], f"the {run.pattern[0]} patterns at mount {run.mount}"
                                            f"{f' ({held})' if held else ''} ({why})")
    return "; ".join([text, *moved.values()])


def sensitivity_table(campaign: Campaign, model: str | None = None) -> pd.DataFrame:
    """DataFrame: rows ``"<pattern> <component>"``, columns every deviation the machine names (its plug-in's names
    where it has them, else its generated ISO symbols) and the setup and mount nuisance bases.

    Values in µm per ″ for angles and µm per µm for lengths, from ``model`` (default the machine's kinematic model:
    ``htm-thesis`` on the thesis machine, else ``chain``) by the complex step where the model allows it, else by
    central differences (:func:`~mtmcal_bayes.models.jacobian_at_zero`); ``attrs["geometry"]`` says which geometry
    (the plug-in's ``sensitivity_geometry`` where it states one), ``attrs["model"]`` the model.
    """
    machine = campaign.machine
    model = default_kinematic_model(machine) if model is None else model
    c = table_campaign(campaign)
    deviations = deviation_quantities(machine)
    space = ParameterSpace(list(c.ballbar.setups), list(c.ballbar.mounts), table=deviations)
    fm = make_model(model, c, space)
    J = units.from_internal(jacobian_at_zero(fm) * space.display_scale(), "um")  # µm per display unit
    cols = list(deviations) + list(SETUP_NUISANCE) + list(MOUNT_NUISANCE)
    rows = {}
    for i, key in enumerate(fm.observations.keys):
        row = dict.fromkeys(cols, 0.0)
        for j, p in enumerate(space.parameters):
            if p.owner in (None, key.setup, key.mount):
                row[p.base] = J[i, j]
        rows[f"{key.pattern} {key.component}"] = row
    df = pd.DataFrame.from_dict(rows, orient="index")[cols]
    df[np.abs(df) < 5e-7] = 0.0
    own = provided(machine, "sensitivity_geometry")
    df.attrs["geometry"] = own(c) if own is not None else _geometry(c, campaign)
    df.attrs["model"] = model
    return df


def to_markdown(df: pd.DataFrame, digits: int = 3) -> str:
    """A Markdown table (blank for zero) of a sensitivity table."""
    head = "| pattern | " + " | ".join(df.columns) + " |"
    sep = "|---|" + "---:|" * len(df.columns)
    lines = [head, sep]
    for idx, row in df.iterrows():
        cells = ["" if v == 0 else f"{v:.{digits}f}" for v in row]
        lines.append(f"| {idx} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


@dataclass
class SensitivityTable:
    """The sensitivity ``table`` of ``model`` (rows ``"<pattern> <component>"``, µm per ″ or per µm) and the
    geometry it was computed with."""

    table: pd.DataFrame
    model: str
    geometry: str

    def to_json(self) -> dict:
        return {"model": self.model, "geometry": self.geometry,
                "unit": "um per arcsec (angles) or um per um (lengths)",
                "sensitivity": {idx: row.to_dict() for idx, row in self.table.iterrows()}}

    def to_markdown(self) -> str:
        return to_markdown(self.table)

    def to_text(self) -> str:
        return "\n".join([
            f"Eccentricity per unit deviation, model {self.model} (µm per ″ for angles, µm per µm for lengths)",
            f"Geometry: {self.geometry}",
            self.table.to_string(float_format=lambda v: "." if v == 0 else f"{v:.3f}")])


def sensitivity(campaign: Campaign, *, model: str | None = None) -> SensitivityTable:
    """:func:`sensitivity_table` as a result with its text, Markdown and JSON forms."""
    df = sensitivity_table(campaign, model)
    return SensitivityTable(df, df.attrs["model"], df.attrs["geometry"])
