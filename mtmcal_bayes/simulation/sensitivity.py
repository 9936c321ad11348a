"""Sensitivity of every pattern's eccentricities to every deviation and mounting offset.

The numbers behind thesis Tables 2.4–2.6 (which show them only as plots): the
Jacobian of a forward model at zero, in µm of eccentricity per ″ (angles) or per
µm (lengths), for all 12 patterns with the geometry of a campaign (its first
tool setup; a mount with R_C = 0 for B patterns and R_C > 0 for C patterns).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .. import units
from ..campaign import Campaign, Run
from ..errors import InputError
from ..machines.plugins import provided
from ..models import jacobian, make_model
from ..parameters import DEVIATIONS, MOUNT_NUISANCE, SETUP_NUISANCE
from ..patterns import B_PATTERNS, C_PATTERNS, COMPONENTS


def _all_patterns_campaign(campaign: Campaign) -> Campaign:
    bb = campaign.ballbar
    setup = next(iter(bb.setups))
    b_mount = next((m.id for m in bb.mounts.values() if m.R_C == 0), None)
    c_mount = next((m.id for m in bb.mounts.values() if m.R_C > 0), None)
    if b_mount is None or c_mount is None:
        have = ", ".join(f"{m.id} R_C_mm = {m.R_C:g}" for m in bb.mounts.values())
        raise InputError(campaign.source, "ballbar.mounts", "the sensitivity table needs a mount with R_C_mm = 0 "
                         f"(B patterns) and one with R_C_mm > 0 (C patterns); have {have}")
    out = copy.deepcopy(campaign)
    out.ballbar.runs = [Run(p, setup, b_mount if p in B_PATTERNS else c_mount,
                            {c: np.zeros(1) for c in COMPONENTS[p]}) for p in B_PATTERNS + C_PATTERNS]
    return out


def sensitivity_table(campaign: Campaign, model: str = "htm-thesis") -> pd.DataFrame:
    """DataFrame: rows ``"<pattern> <component>"``, columns deviations and nuisance bases.

    Values in µm per ″ for angles and µm per µm for lengths; index names the
    geometry used in ``attrs["geometry"]``.
    """
    c = _all_patterns_campaign(campaign)
    fm = make_model(model, c)
    J = units.from_internal(jacobian(fm) * fm.space.display_scale(), "um")  # µm per display unit
    cols = list(DEVIATIONS) + list(SETUP_NUISANCE) + list(MOUNT_NUISANCE)
    rows = {}
    for i, key in enumerate(fm.observations.keys):
        row = dict.fromkeys(cols, 0.0)
        for j, p in enumerate(fm.space.parameters):
            if p.owner in (None, key.setup, key.mount):
                row[p.base] = J[i, j]
        rows[f"{key.pattern} {key.component}"] = row
    df = pd.DataFrame.from_dict(rows, orient="index")[cols]
    df[np.abs(df) < 5e-7] = 0.0
    s = c.ballbar.setups[c.ballbar.runs[0].setup]
    cm = c.ballbar.mounts[c.ballbar.runs[-1].mount]
    df.attrs["geometry"] = (f"R_B = {s.R_B:g} mm, Z_T = {s.Z_T:g} mm, X_T = {s.X_T:g} mm, "
                            f"Z_C = {cm.Z_C:g} mm, R_C = {cm.R_C:g} mm, L_B = {c.ballbar.length:g} mm, "
                            f"CR geometry {c.ballbar.cr_geometry}")
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


def described_sensitivity_table(campaign: Campaign, model: str = "chain") -> pd.DataFrame:
    """A described machine's table (SPEC §19, the generalised Tables 2.4–2.6): every pattern ``<K><d>`` of the
    machine, each on the campaign's first tool setup and, per swivelled axis, the mount and held positions of the
    campaign's first run of that axis (else its first mount, the other axes at 0); columns every generated
    deviation and the setup and mount nuisance bases (a ball on the swivelled axis' line takes the radial direction of
    :func:`~mtmcal_bayes.machines.patterns.pattern_commands`)."""
    from ..machines import generated
    from ..machines.patterns import axis_of, components, patterns_of
    from ..machines.space import described_space
    from ..models.chain_models import complex_step_jacobian

    desc = campaign.machine.description
    bb = campaign.ballbar
    setup = next(iter(bb.setups))
    runs = []
    for pattern in patterns_of(desc):
        first = next((r for r in bb.runs if r.pattern[0] == pattern[0]), None)
        mount = first.mount if first is not None else next(iter(bb.mounts))
        hold = first.hold_deg if first is not None else None
        from ..machines.patterns import default_arc_deg

        runs.append(Run(pattern, setup, mount, {c: np.zeros(1) for c in components(desc, pattern)},
                        arc_deg=default_arc_deg(axis_of(desc, pattern)), hold_deg=hold))
    c = copy.deepcopy(campaign)
    c.ballbar.runs, c.probe = runs, None
    space = described_space(c, [d.name for d in generated(desc)], data="ballbar")
    fm = make_model(model, c, space)
    J = units.from_internal(complex_step_jacobian(fm) * space.display_scale(), "um")
    cols = [d.name for d in generated(desc)] + list(SETUP_NUISANCE) + list(MOUNT_NUISANCE)
    rows = {}
    for i, key in enumerate(fm.observations.keys):
        row = dict.fromkeys(cols, 0.0)
        for j, p in enumerate(space.parameters):
            if p.owner in (None, key.setup, key.mount):
                row[p.base] = J[i, j]
        rows[f"{key.pattern} {key.component}"] = row
    df = pd.DataFrame.from_dict(rows, orient="index")[cols]
    df[np.abs(df) < 5e-7] = 0.0
    df.attrs["geometry"] = (f"{desc.configuration}; tool setup {setup} (R_B = {bb.setups[setup].R_B:g} mm), "
                            f"L_B = {bb.length:g} mm; mounts and held axes of the campaign's runs")
    return df


def sensitivity(campaign: Campaign, *, model: str = "htm-thesis") -> SensitivityTable:
    """:func:`sensitivity_table` (a described machine's: :func:`described_sensitivity_table`, model ``chain`` or
    ``linear``, the same numbers) as a result with its text, Markdown and JSON forms."""
    own = provided(campaign.machine, "sensitivity_table")  # the thesis' Tables 2.4–2.6 in its campaign format
    if own is None:
        df = described_sensitivity_table(campaign, "linear" if model == "linear" else "chain")
        return SensitivityTable(df, df.attrs.get("model", "chain"), df.attrs["geometry"])
    df = own(campaign, model)
    return SensitivityTable(df, model, df.attrs["geometry"])
