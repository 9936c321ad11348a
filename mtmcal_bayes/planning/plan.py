"""Rank candidate measurements, sweep the tool length, check by Monte Carlo: the result of ``plan``."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .. import units
from ..parameters import data_instruments
from .candidates import Candidate
from .catalogue import sweep_candidates
from .machine_kit import catalogue_of, feasibility_of, kit_of, planner_for
from .design import MAX_RUNS, SIGMA_CONTRACTION, Planner, SigmaInformation
from .preposterior import current_posterior, realised_sd
from ..machine_time import TimeModel
from .probe_catalogue import PROBE_NOTE, ProbeCandidate, probe_catalogue, probe_feasibility
from .rtest_catalogue import RTestCandidate, rtest_catalogue, rtest_feasibility, rtest_note
from .scale_priors import learnt_notes, learnt_summary, scale_prior

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
    #: what the campaign and the candidates teach about sigma_model (:func:`sigma_summary`); the per-candidate
    #: values are the table's sigma_model_* columns
    sigma_model: dict = field(default_factory=dict)
    #: each R-test candidate's ``[[rtest.runs]]`` table by name (angles_deg, sphere_mm, nest, frame, zero): add it
    #: to the campaign and ``ncgen --rtest`` writes its program
    rtest_runs: dict = field(default_factory=dict)

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
            num = lambda v: None if pd.isna(v) else float(v)  # noqa: E731  (a probe run has no Z_T, no bar)
            cands.append({
                "rank": int(r["rank"]), "name": r["name"], "kind": r["kind"], "pattern": r["pattern"],
                "setup": r["setup"], "R_B_mm": num(r["R_B_mm"]), "Z_T_mm": num(r["Z_T_mm"]), "mount": r["mount"],
                "R_C_mm": num(r["R_C_mm"]), "L_B_mm": num(r["L_B_mm"]), "repeats": int(r["repeats"]),
                "feasible": bool(r["feasible"]), "feasibility": r["feasibility"], "verdict": r["verdict"],
                "targets": {t: {"sd_before": r[f"{t} sd_before"], "sd_after": r[f"{t} sd_after"], "unit": u}
                            for t, u in zip(self.targets, self.target_units)},
                "newly_identified": [t for t in r["newly_identified"].split(", ") if t],
                "eig_bits": r["eig_bits"],
                "sigma_model_contraction": r["sigma_model_contraction"], "sigma_model_rank": int(r["sigma_model_rank"]),
                "sigma_model_runs_needed": None if pd.isna(r["sigma_model_runs_needed"])
                else int(r["sigma_model_runs_needed"]),
            })
            if r["kind"] == "rtest":
                cands[-1].update(minutes=float(r["minutes"]), rtest_run=self.rtest_runs[r["name"]])
        ranked = self.table.sort_values("sigma_model_rank")
        sigma = {**self.sigma_model, "ranking": [str(n) for n in ranked.loc[ranked["feasible"], "name"]]}
        return {"model": self.model, "targets": self.targets, "sigma_model_um": self.sigma_model_um, "candidates": cands,
                "sigma_model_information": sigma,
                "sweep": {"pattern": self.sweep_pattern, "rows": self.sweep.to_dict(orient="records")},
                "monte_carlo_check": self.check.to_dict(orient="records"), "notes": self.notes}


def _verdict(feasible: bool, why: str, informative: bool) -> str:
    if not feasible:
        return f"infeasible: {why}"
    return "ok" if informative else "identifies nothing new for the targets"


def _table(planner: Planner, candidates: list[Candidate], campaign) -> pd.DataFrame:
    return _tables(planner, candidates, campaign)[0]


def rtest_where(c: RTestCandidate) -> dict:
    """The geometry columns of an R-test candidate: its nest (length in ``R_B_mm``) and its sphere (named by its
    placement where the campaign's R-test runs give it one; a campaign without R-test runs has the default
    placement, named "sphere" itself: "sphere at [...] mm")."""
    s = c.setup
    name = f"sphere {s.placement}" if s.measured else "sphere"
    return {"setup": f"nest {s.nest} {s.length:g} mm", "R_B_mm": s.length, "Z_T_mm": np.nan,
            "mount": f"{name} at [" + ", ".join(f"{x:g}" for x in s.sphere) + "] mm", "R_C_mm": np.nan}


def _tables(planner: Planner, candidates: list[Candidate], campaign,
            times: TimeModel | None = None) -> tuple[pd.DataFrame, SigmaInformation]:
    """The ranked table and what the candidates would teach about sigma_model (one set of candidate rows); with
    R-test candidates, a ``minutes`` column: theirs from ``times`` (default the time model's defaults)."""
    made = planner.candidate_rows(candidates)
    ev = planner.evaluate(candidates, rows=made)
    si = planner.sigma_information(candidates, rows=made)
    rows = []
    kit = kit_of(campaign)
    fits = feasibility_of(campaign)
    timed = any(isinstance(c, RTestCandidate) for c in candidates)
    times = times or TimeModel()
    for k, c in enumerate(candidates):
        probe, rtest = isinstance(c, ProbeCandidate), isinstance(c, RTestCandidate)
        ok, why = probe_feasibility(c, campaign) if probe else rtest_feasibility(c, campaign) if rtest else fits(c)
        newly = [t for i, t in enumerate(ev.targets) if ev.identified_after[k, i] and not ev.identified_before[i]]
        where = ({"setup": f"stylus {c.stylus_length:g} mm", "R_B_mm": c.stylus_length, "Z_T_mm": np.nan,
                  "mount": f"sphere at Z_C {c.Z_C:g} mm", "R_C_mm": c.R_C} if probe else
                 rtest_where(c) if rtest else kit.where(c))
        row = {"name": c.name, "kind": c.kind, "pattern": c.pattern, **where, "L_B_mm": c.length,
               "repeats": c.repeats, **({"minutes": c.minutes(times) if rtest else np.nan} if timed else {}),
               "extension_mm": c.extension, "feasible": ok, "feasibility": why,
               "eig_bits": float(ev.eig_bits[k]), "informative": bool(ev.informative[k]),
               "newly_identified": ", ".join(newly), "verdict": _verdict(ok, why, bool(ev.informative[k])),
               "sigma_model_contraction": float(si.contraction[k]),
               # 0: the contraction is reached already (a learnt prior); None: not within MAX_RUNS runs
               "sigma_model_runs_needed": 0 if si.contraction_now >= SIGMA_CONTRACTION
               else int(si.runs_needed[k]) or None}
        for i, t in enumerate(ev.targets):
            row[f"{t} sd_before"] = float(ev.sd_before[i])
            row[f"{t} sd_after"] = float(ev.sd_after[k, i])
        rows.append(row)
    df = pd.DataFrame(rows)
    tier = np.where(~df["feasible"], 2, np.where(df["informative"], 0, 1))  # useful, useless, infeasible
    order = np.lexsort((-df["eig_bits"].to_numpy(), tier))
    df = df.iloc[order].reset_index(drop=True)
    df.insert(0, "rank", np.arange(1, len(df) + 1))
    df["sigma_model_runs_needed"] = df["sigma_model_runs_needed"].astype("Int64")  # <NA>: not within MAX_RUNS
    # ranking by what a run teaches about sigma_model: feasible first, then the contraction, then fewer runs
    runs = df["sigma_model_runs_needed"].fillna(MAX_RUNS + 1).to_numpy(dtype=float)
    by_sigma = np.lexsort((df["rank"].to_numpy(), runs, -df["sigma_model_contraction"].to_numpy(),
                           ~df["feasible"].to_numpy(dtype=bool)))
    df["sigma_model_rank"] = 0
    df.loc[by_sigma, "sigma_model_rank"] = np.arange(1, len(df) + 1)
    return df, si


def tool_length_sweep(planner: Planner, campaign, pattern: str, extensions=SWEEP_MM) -> pd.DataFrame:
    """Expected target sds for ``pattern`` at the primary setup plus each extension (mm)."""
    kit = kit_of(campaign)
    cands = sweep_candidates(campaign, pattern, extensions)
    ev = planner.extended(cands).evaluate()
    rows = []
    fits = feasibility_of(campaign)
    for k, (c, e) in enumerate(zip(cands, extensions)):
        ok, why = fits(c)
        row = {"extension_mm": float(e), "R_B_mm": c.setup.R_B, "Z_T_mm": kit.where(c)["Z_T_mm"],
               "feasible": ok,
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
    if planner.data != "ballbar":  # the check's exact posterior has one scale for all rows: the ball bar's alone
        return pd.DataFrame()
    picked = [r for _, r in table.iterrows() if r["feasible"] and r["kind"] not in ("repeats", "probe", "rtest")][:n]
    rows = []
    now = current_posterior(planner) if picked else None
    for r in picked:
        mc = realised_sd(planner, index[r["name"]], n_sim=n_sim, seed=seed, now=now)
        for i, (t, u) in enumerate(zip(planner.targets, planner.target_units)):
            closed = r[f"{t} sd_after"]
            rows.append({"candidate": r["name"], "target": t, "unit": u, "sd_before_closed_form": r[f"{t} sd_before"],
                         "sd_before_exact": float(mc["sd_now"][i]), "sd_after_closed_form": closed,
                         "sd_after_monte_carlo": float(mc["sd_realised"][i]),
                         "relative_difference": float(mc["sd_realised"][i] / closed - 1.0), "n_sim": n_sim})
    return pd.DataFrame(rows)


def best_measurement(campaign, target: str, *, sigma_model_um: float | None = None,
                     model: str = "linear", data: str = "ballbar") -> dict | None:
    """The ball-bar catalogue measurement of ``campaign``'s machine that would make ``target`` most certain given the
    campaign's ``data`` (closed form): ``name``, ``sd_before``, ``sd_after`` (display units) and ``unit``; None when
    no feasible candidate helps."""
    candidates = catalogue_of(campaign)
    sigma = None if sigma_model_um is None else units.to_internal(sigma_model_um, "um")
    planner = planner_for(campaign, candidates, [target], sigma_model=sigma, model=model, data=data)
    table = _table(planner, candidates, campaign)
    useful = table[table["feasible"] & table["informative"]]
    if useful.empty:
        return None
    best = useful.loc[useful[f"{target} sd_after"].idxmin()]
    return {"name": str(best["name"]), "sd_before": float(best[f"{target} sd_before"]),
            "sd_after": float(best[f"{target} sd_after"]), "unit": planner.target_units[0]}


def plan(campaign, targets=None, *, extra: list[Candidate] | None = None, sigma_model_um: float | None = None,
         sweep_pattern: str | None = None, model: str = "linear", data: str = "ballbar",
         sigma_prior=None, times: TimeModel | None = None) -> PlanResult:
    """Rank the catalogue — ball-bar runs and, with a ``[probe]``, touch-probe runs — plus ``extra`` user candidates
    for ``targets``, given the campaign's ``data`` (a value of :data:`~mtmcal_bayes.models.DATA`); sweep the tool length;
    check three by Monte Carlo (ball-bar data).  ``sigma_prior``: a
    :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior` learnt elsewhere (None: the assumed priors): the closed form's
    σ_model (unless ``sigma_model_um``) and the probe's scale are the rms of its priors, and the σ_model information
    and the Monte-Carlo check use it (:class:`.design.Planner`).  With an ``[rtest]``, R-test runs are candidates
    too (:mod:`.rtest_catalogue`), each with its machine minutes under ``times`` (default the time model's defaults);
    a campaign without a ball-bar set-up but with probe or R-test candidates has no ball-bar candidates and no
    sweep."""
    kit = kit_of(campaign)
    others = probe_catalogue(campaign) + rtest_catalogue(campaign)
    ballbar = [c for c in catalogue_of(campaign) if data != "probe" or c.repeat_of is None] \
        if campaign.ballbar.setups or not others else []
    candidates = ballbar + others + list(extra or [])
    sigma = None if sigma_model_um is None else units.to_internal(sigma_model_um, "um")
    planner = planner_for(campaign, candidates, targets, sigma_model=sigma, model=model, data=data,
                          sigma_prior=sigma_prior)
    table, si = _tables(planner, candidates, campaign, times)
    if not ballbar:  # nothing to sweep: no ball-bar set-up
        sweep_pattern, sweep = "", pd.DataFrame()
    else:
        if sweep_pattern is None:
            sweep_pattern = kit.sweep_pattern(table, campaign)
        sweep = tool_length_sweep(planner, campaign, sweep_pattern)
    check = monte_carlo_check(planner, table)
    form = "the linear model" if model == "linear" else f"the {model} model linearised at zero deviations"
    learnt = " learnt elsewhere" if planner.learnt is not None and sigma_model_um is None else ""
    bar_runs = (f"; new runs measured {candidates[0].repeats if candidates else 3} times with repeat sd "
                f"{units.from_internal(planner.pooled_sd, 'um'):.2f} µm (pooled from the campaign) and instrument "
                f"accuracy {units.from_internal(campaign.ballbar.accuracy, 'um'):g} µm") \
        if ballbar or not others else ""
    notes = [f"closed form for {form} at sigma_model = {units.from_internal(planner.sigma_model, 'um'):.2f} µm "
             f"(the root mean square of its prior{learnt}){bar_runs}",
             kit.feasibility_note,
             (PROBE_NOTE.format(sigma_probe=units.from_internal(planner.sigma_probe, 'um'))
              if any(isinstance(c, ProbeCandidate) for c in candidates) else
              "no touch-probe candidates: the campaign has no [probe] with a repeatability and a stylus")]
    rtests = [c for c in candidates if isinstance(c, RTestCandidate)]
    if rtests:
        notes.append(rtest_note(campaign, rtests, planner.sigma_rtest))
    if not ballbar:
        notes.append("no ball-bar candidates and no tool-length sweep: the campaign has no ball-bar set-up")
    cols = [c for c in sweep.columns if c.endswith(" sd_after")]
    if len(sweep) > 1 and np.allclose(sweep[cols].to_numpy(), sweep[cols].to_numpy()[0], rtol=1e-6):
        notes.append(f"the tool-length sweep of {sweep_pattern} is flat: a longer tool teaches nothing more here "
                     "(on a machine whose spindle no rotary axis carries, the tool length moves no lever)")
    if planner.not_targeted and not targets:
        notes.append(f"not targeted: {', '.join(planner.not_targeted)} — no run of the catalogue determines them one "
                     "by one (identifiability of the campaign and every candidate together, the T ball centred)")
    if data != "ballbar":
        notes.append(f"the current posterior rests on {_resting_on(data, campaign)}: the "
                     "sigma_model information and the Monte-Carlo check (one scale for all data) are for ball-bar "
                     "data only and are not given here")
    if planner.sigma_model == 0.0:
        notes.append("at sigma_model = 0 the data carry no Fisher information about sigma_model (its variance "
                     "enters as sigma_model²): the sigma_model ranking needs a positive sigma_model_um")
    notes += learnt_notes(campaign, planner.learnt, "used by the closed form's sigma_model, the σ_model information "
                          "and the Monte-Carlo check")
    return PlanResult(table, sweep, check, planner.targets, planner.target_units,
                      units.from_internal(planner.sigma_model, "um"), sweep_pattern, model, notes, campaign.source,
                      sigma_model=sigma_summary(planner, si) if data == "ballbar" else {},
                      rtest_runs={c.name: rtest_run_table(c) for c in rtests})


def rtest_run_table(c: RTestCandidate) -> dict:
    """An R-test candidate as its ``[[rtest.runs]]`` table, without readings (docs/rtest.md)."""
    s = c.setup
    return {"id": c.name, "nest": s.nest, "sphere_mm": list(s.sphere), "angles_deg": c.angles_deg(),
            "frame": s.frame, "zero": s.zero, "repeats": c.repeats, **({"swept": True} if c.sweep_span else {})}


def _resting_on(data: str, campaign) -> str:
    """The instruments the current posterior rests on, in words (the ball bar's and the probe's as before)."""
    if data in ("both", "probe"):
        return "both instruments" if data == "both" else "the probe"
    words = {"ballbar": "the ball bar", "probe": "the touch probe", "rtest": "the R-test"}
    return " and ".join(words[i] for i in data_instruments(data, campaign))


def sigma_summary(planner: Planner, si: SigmaInformation) -> dict:
    """The campaign's closed-form sigma_model contraction and how it is computed (JSON-ready); under a learnt prior
    also ``prior_source`` and what the contraction is measured against (``contraction_reference``)."""
    um2 = units.to_internal(1.0, "um") ** 2
    out = {"prior": scale_prior(planner.campaign, "sigma_model", planner.learnt).describe(),
           "prior_sd_um": units.from_internal(float(np.sqrt(si.prior_var)), "um"),
           "evaluated_at_um": units.from_internal(si.sigma, "um"), "means": int(len(planner.observations)),
           "fisher_now_per_um2": si.fisher_now * um2, "contraction_now": si.contraction_now,
           "target_contraction": SIGMA_CONTRACTION, "max_runs": MAX_RUNS,
           "method": "Laplace: var_post = 1/(1/var_prior + I), I = 2 sigma^2 tr(C^-2) the Fisher information of "
                     "the marginal likelihood, C = A Sigma0 A^T + diag(base_var + sigma^2); contraction = "
                     "1 - var_post/var_prior; a candidate's runs after the first each on its own W-ball placement"}
    if planner.learnt is not None:
        out["method"] = out["method"].replace("1 - var_post/var_prior", "1 - var_post/max(var_assumed, var_learnt)")
    return out | learnt_summary(planner.campaign, planner.learnt)
