"""Rank candidate measurements, sweep the tool length, check by Monte Carlo: the result of ``plan``."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .. import units
from .candidates import (
    Candidate,
    candidate_mount,
    catalogue,
    extended_setup,
    feasibility,
)
from .design import Planner
from .preposterior import realised_sd

#: tool-length differences of the sweep, mm
SWEEP_MM = np.arange(0.0, 250.0 + 1e-9, 5.0)
N_CHECKED = 3


@dataclass
class PlanResult:
    """Ranked candidates (best first), the tool-length sweep and the Monte-Carlo check."""

    table: pd.DataFrame
    sweep: pd.DataFrame
    check: pd.DataFrame
    targets: list[str]
    target_units: list[str]
    sigma_model_um: float
    sweep_pattern: str
    model: str = "linear"
    notes: list[str] = field(default_factory=list)
    campaign: str = ""
    output: str | None = None  # directory written by :meth:`write`
    files: list[str] = field(default_factory=list)

    def write(self, out_dir) -> list[str]:
        """Write plan.csv, plan_sweep.csv, plan_check.csv, plan.json and the figures into ``out_dir``."""
        from .output import write_plan

        self.files = write_plan(self, out_dir)
        self.output = str(out_dir)
        return self.files

    def to_json(self) -> dict:
        """What ``plan --json`` prints: :meth:`document` and where it was written."""
        return {**self.document(), "campaign": self.campaign, "output": self.output, "files": self.files}

    def to_text(self) -> str:
        """What ``plan`` prints."""
        from .output import format_plan

        text = format_plan(self)
        if self.files:
            text += f"\n\nplan written to {self.output}/: {', '.join(self.files)}"
        return text

    def document(self) -> dict:
        """The plan as JSON (plan.json): ranked candidates, sweep, Monte-Carlo check, notes."""
        cands = []
        for _, r in self.table.iterrows():
            cands.append({
                "rank": int(r["rank"]), "name": r["name"], "kind": r["kind"], "pattern": r["pattern"],
                "setup": r["setup"], "R_B_mm": r["R_B_mm"], "Z_T_mm": r["Z_T_mm"], "mount": r["mount"],
                "R_C_mm": r["R_C_mm"], "L_B_mm": r["L_B_mm"], "repeats": int(r["repeats"]),
                "feasible": bool(r["feasible"]), "feasibility": r["feasibility"], "verdict": r["verdict"],
                "targets": {t: {"sd_before": r[f"{t} sd_before"], "sd_after": r[f"{t} sd_after"], "unit": u}
                            for t, u in zip(self.targets, self.target_units)},
                "newly_identified": [t for t in r["newly_identified"].split(", ") if t],
                "eig_bits": r["eig_bits"],
            })
        return {"model": self.model, "targets": self.targets, "sigma_model_um": self.sigma_model_um, "candidates": cands,
                "sweep": {"pattern": self.sweep_pattern, "rows": self.sweep.to_dict(orient="records")},
                "monte_carlo_check": self.check.to_dict(orient="records"), "notes": self.notes}


def _verdict(feasible: bool, why: str, informative: bool) -> str:
    if not feasible:
        return f"infeasible: {why}"
    return "ok" if informative else "identifies nothing new for the targets"


def _table(planner: Planner, candidates: list[Candidate], campaign) -> pd.DataFrame:
    ev = planner.evaluate(candidates)
    rows = []
    for k, c in enumerate(candidates):
        ok, why = feasibility(c, campaign)
        newly = [t for i, t in enumerate(ev.targets) if ev.identified_after[k, i] and not ev.identified_before[i]]
        row = {"name": c.name, "kind": c.kind, "pattern": c.pattern, "setup": c.setup.id, "R_B_mm": c.setup.R_B,
               "Z_T_mm": c.setup.Z_T, "mount": c.mount.id, "R_C_mm": c.mount.R_C, "L_B_mm": c.length,
               "repeats": c.repeats, "extension_mm": c.extension, "feasible": ok, "feasibility": why,
               "eig_bits": float(ev.eig_bits[k]), "informative": bool(ev.informative[k]),
               "newly_identified": ", ".join(newly), "verdict": _verdict(ok, why, bool(ev.informative[k]))}
        for i, t in enumerate(ev.targets):
            row[f"{t} sd_before"] = float(ev.sd_before[i])
            row[f"{t} sd_after"] = float(ev.sd_after[k, i])
        rows.append(row)
    df = pd.DataFrame(rows)
    tier = np.where(~df["feasible"], 2, np.where(df["informative"], 0, 1))  # useful, useless, infeasible
    order = np.lexsort((-df["eig_bits"].to_numpy(), tier))
    df = df.iloc[order].reset_index(drop=True)
    df.insert(0, "rank", np.arange(1, len(df) + 1))
    return df


def tool_length_sweep(planner: Planner, campaign, pattern: str, extensions=SWEEP_MM) -> pd.DataFrame:
    """Expected target sds for ``pattern`` at the primary setup plus each extension (mm)."""
    base = campaign.primary_setup()
    cands = [Candidate(f"{pattern} @ R_B+{e:g} mm", "sweep", pattern, extended_setup(base, e),
                       candidate_mount(campaign, pattern), campaign.ballbar.length, extension=float(e)) for e in extensions]
    sub = Planner(campaign, cands, planner.targets, sigma_model=planner.sigma_model, model=planner.model)
    ev = sub.evaluate()
    rows = []
    for k, (c, e) in enumerate(zip(cands, extensions)):
        ok, why = feasibility(c, campaign)
        row = {"extension_mm": float(e), "R_B_mm": c.setup.R_B, "Z_T_mm": c.setup.Z_T, "feasible": ok,
               "eig_bits": float(ev.eig_bits[k]),
               "verdict": _verdict(ok, why, bool(ev.informative[k]))}
        for i, t in enumerate(ev.targets):
            row[f"{t} sd_after"] = float(ev.sd_after[k, i])
            row[f"{t} sd_before"] = float(ev.sd_before[i])
            row[f"{t} identified"] = bool(ev.identified_after[k, i])
        rows.append(row)
    return pd.DataFrame(rows)


def monte_carlo_check(planner: Planner, table: pd.DataFrame, *, n: int = N_CHECKED, n_sim: int = 400,
                      seed: int = 0) -> pd.DataFrame:
    """Closed-form expected sd against the Monte-Carlo realised sd for the ``n`` best new runs."""
    index = {c.name: i for i, c in enumerate(planner.candidates)}
    picked = [r for _, r in table.iterrows() if r["feasible"] and r["kind"] != "repeats"][:n]
    rows = []
    for r in picked:
        mc = realised_sd(planner, index[r["name"]], n_sim=n_sim, seed=seed)
        for i, (t, u) in enumerate(zip(planner.targets, planner.target_units)):
            closed = r[f"{t} sd_after"]
            rows.append({"candidate": r["name"], "target": t, "unit": u, "sd_before_closed_form": r[f"{t} sd_before"],
                         "sd_before_exact": float(mc["sd_now"][i]), "sd_after_closed_form": closed,
                         "sd_after_monte_carlo": float(mc["sd_realised"][i]),
                         "relative_difference": float(mc["sd_realised"][i] / closed - 1.0), "n_sim": n_sim})
    return pd.DataFrame(rows)


def best_measurement(campaign, target: str, *, sigma_model_um: float | None = None,
                     model: str = "linear") -> dict | None:
    """The catalogue measurement that would make ``target`` most certain (closed form): ``name``,
    ``sd_before``, ``sd_after`` (display units) and ``unit``; None when no feasible candidate helps."""
    candidates = catalogue(campaign)
    sigma = None if sigma_model_um is None else units.to_internal(sigma_model_um, "um")
    planner = Planner(campaign, candidates, [target], sigma_model=sigma, model=model)
    table = _table(planner, candidates, campaign)
    useful = table[table["feasible"] & table["informative"]]
    if useful.empty:
        return None
    best = useful.loc[useful[f"{target} sd_after"].idxmin()]
    return {"name": str(best["name"]), "sd_before": float(best[f"{target} sd_before"]),
            "sd_after": float(best[f"{target} sd_after"]), "unit": planner.target_units[0]}


def plan(campaign, targets=None, *, extra: list[Candidate] | None = None, sigma_model_um: float | None = None,
         sweep_pattern: str | None = None, model: str = "linear") -> PlanResult:
    """Rank the catalogue (plus ``extra`` user candidates) for ``targets``; sweep; check three by Monte Carlo."""
    candidates = catalogue(campaign) + list(extra or [])
    sigma = None if sigma_model_um is None else units.to_internal(sigma_model_um, "um")
    planner = Planner(campaign, candidates, targets, sigma_model=sigma, model=model)
    table = _table(planner, candidates, campaign)
    if sweep_pattern is None:
        best = table[table["kind"] == "tool length"]
        sweep_pattern = str(best.iloc[0]["pattern"]) if len(best) else "CR"
    sweep = tool_length_sweep(planner, campaign, sweep_pattern)
    check = monte_carlo_check(planner, table)
    form = "the linear model" if model == "linear" else f"the {model} model linearised at zero deviations"
    notes = [f"closed form for {form} at sigma_model = {units.from_internal(planner.sigma_model, 'um'):.2f} µm "
             "(the root mean square of its prior); new runs measured "
             f"{candidates[0].repeats if candidates else 3} times with repeat sd "
             f"{units.from_internal(planner.pooled_sd, 'um'):.2f} µm (pooled from the campaign) and instrument "
             f"accuracy {units.from_internal(campaign.ballbar.accuracy, 'um'):g} µm",
             "feasible = the span of each linear-axis command fits the axis travel of [machine] (the campaign "
             "does not give where the C axis sits within the travels)",
             "touch-probe measurements are not candidates: the probe data are compared with, not part of, the "
             "likelihood"]
    return PlanResult(table, sweep, check, planner.targets, planner.target_units,
                      units.from_internal(planner.sigma_model, "um"), sweep_pattern, model, notes, campaign.source)
