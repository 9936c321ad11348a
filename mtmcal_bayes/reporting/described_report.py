"""The report of a campaign on a described machine (SPEC §19): every section of the thesis machine's report that
applies, and none that claims a thesis number.

Written like :func:`~.build.build_report` (into a temporary directory, moved into place at the end): the machine
(its description and chain, figures of its chain and of its location errors), the posterior of its deviations
under their ISO 230-7 symbols, what the campaign determines (one by one, in combination, not at all: computed from
its Jacobian) with each combination's posterior, the least-squares identification beside the posterior, the
stated truth of a simulated campaign beside both, the uncertainty statement and budget, the joint posterior and
the sampler's diagnostics.  What the thesis machine's report has and this one does not is said in a box.
"""

from __future__ import annotations

import time
from pathlib import Path

import pandas as pd

from .. import units
from ..html_page import Page
from ..io.netcdf import write_netcdf_atomic
from ..io.textfiles import atomic_directory
from ..posterior.consistency import DATA_LABELS
from ..posterior.least_squares import LeastSquares, least_squares
from ..posterior.output import format_posterior, identifiability_block
from ..posterior.sample import sample_posterior
from ..progress import ProgressEvent, emit
from ..posterior.loo import loo_check
from . import budget_plot, corner_plot, forest, loo_plot, machine_figure, mcmc_plots, ppc
from .build import (
    Report,
    _budget_section,
    _check_output_dir,
    _meta,
    _statement_section,
    budget_table,
    priors_table,
    sampler_paragraph,
    summary_table,
)
from .decisions import add_suggestions
from .drawing import Drawing

#: what the thesis machine's report has and a described machine's does not (yet), and why
NOT_MADE = [
    "the thesis' deterministic identification (Tables 4.5, 5.3): the thesis machine's formulas; here the "
    "least-squares identification of the chain's first order stands beside the posterior",
    "the plan of the next measurement, the compensation of NC programs and the polar ΔL trajectories: not yet for "
    "a described machine (the next issue: the whole workflow on any machine)",
    "the three posteriors of the instruments side by side and their consistency check: the fused posterior is "
    "shown; sample --data ballbar / probe gives each alone",
]

CHAIN_CAPTION = ("The machine at its home pose: the frame, each rotary axis' nominal line through its point, the "
                 "spindle and a tool of the campaign's length (the key says whose), the linear axes (primed: they "
                 "move the workpiece); the chain from workpiece to tool below.")
DEVIATIONS_CAPTION = ("What each location error means (positive values, exaggerated), as the chain applies it: a "
                      "small rigid displacement of the body the axis carries, turning about the axis' point.")


CORNER_CAPTION = ("Corner plot of the posterior of the deviations this campaign determines (one by one or in "
                  "combination). Diagonal: marginal histograms with the posterior mean ± sd as title. Off-diagonal: "
                  "2-D histograms with contours enclosing 68 % and 95 % of the posterior mass; a narrow diagonal "
                  "ridge is a combination the data determine better than its terms.")


def build_described_report(analysis, out_dir, *, settings, progress=None, command: str = "",
                           tolerances: dict | None = None) -> Report:
    """Sample, draw, tabulate and write the report of a described machine's ``analysis`` into ``out_dir``;
    ``tolerances`` (``{name: Tolerance}`` by the machine's names; default the campaign's own) add the conformity
    decisions, each undecided one with the planner's next measurement."""
    t0 = time.perf_counter()
    out_dir = Path(out_dir)
    _check_output_dir(out_dir)
    campaign, model, data = analysis.campaign, analysis.model, analysis.data
    desc = campaign.machine.description

    def say(text: str) -> None:
        emit(progress, ProgressEvent("report", text))

    with atomic_directory(out_dir) as tmp:
        drawing = Drawing(tmp)
        try:
            tool = machine_figure.campaign_tool(campaign)
            drawing.start([("machine.png", lambda: machine_figure.chain_figure(desc, tool)),
                           ("deviations.png", lambda: machine_figure.deviations_figure(desc))])
            say(f"sampling the posterior ({model}, {DATA_LABELS[data]})")
            rep = sample_posterior(analysis, settings=settings, progress=progress, tolerances=tolerances)
            if rep.conformity is not None and not rep.conformity.empty:
                say("asking the planner how to decide the undecided tolerances")
                add_suggestions(rep, campaign)
            deviations = [p.name for p in rep.log_posterior.space.parameters if p.group == "deviation"]
            determined = list(rep.identifiability.determined) + [
                n for c in rep.identifiability.combinations for n in c.weights if n not in rep.identifiability.determined]
            shown = [n for n in deviations if n in set(determined)] or deviations
            loo = loo_check(rep.idata)
            ppc_df = None
            if campaign.ballbar.runs and data != "probe":  # the eccentricities the posterior saw
                ppc_df = ppc.ppc_table(rep.idata, campaign, analysis.ballbar_observations)
            # one batch, the longest first: its two processes end together
            drawing.start([("corner.png", lambda: corner_plot.corner_figure(rep.idata, rep.comparison, names=shown)),
                           ("sigma_model.png", lambda: budget_plot.sigma_figure(rep, names=shown)),
                           ("forest.png", lambda: forest.forest_figure({model: rep.summary}, None, names=deviations)),
                           *([("ppc.png", lambda: ppc.ppc_figure({model: ppc_df}, campaign))] if ppc_df is not None
                             else []),
                           ("loo.png", lambda: loo_plot.loo_figure(loo)),
                           ("trace.png", lambda: mcmc_plots.trace_figure(rep.sampling, names=shown)),
                           ("rank.png", lambda: mcmc_plots.rank_figure(rep.idata, names=shown)),
                           ("budget.png", lambda: budget_plot.budget_figure(rep.summary)),
                           ("posterior.nc", lambda: write_netcdf_atomic(rep.idata, tmp / "posterior.nc"))])
            ls = least_squares(rep.log_posterior, rep.identifiability, units.to_internal(rep.sigma_model_um, "um"))
            tables = _tables(rep, ls, campaign)
            tables["loo.csv"] = (loo.table, True)
            if ppc_df is not None:
                tables["ppc.csv"] = (ppc_df, True)
            drawing.finish()
        finally:
            drawing.stop()
        files = [n for n in ("machine.png", "deviations.png", "corner.png", "forest.png", "ppc.png", "loo.png",
                             "budget.png", "sigma_model.png", "rank.png", "trace.png") if (tmp / n).exists()]
        for name, (df, index) in tables.items():
            df.to_csv(tmp / name, index=index, float_format="%.6g")
            files.append(name)
        page = _page(rep, ls, tables, campaign=campaign, tmp=tmp, loo=loo, shown=shown)
        elapsed = time.perf_counter() - t0
        files = ["index.html"] + files + ["posterior.nc"]
        page.write(tmp / "index.html", _meta(campaign, model, rep.sampling.settings.seed, command=command,
                                             elapsed=elapsed))
    console = "\n".join([format_posterior(rep), "", identifiability_block(rep.identifiability, rep.combinations),
                         "", f"report written to {out_dir}/ in {elapsed:.0f} s: " + ", ".join(files),
                         f"open {out_dir / 'index.html'} in a browser"])
    return Report(out_dir, files, tables["summary.csv"][0], console, elapsed, rep, [])


def _tables(rep, ls: LeastSquares, campaign) -> dict[str, tuple[pd.DataFrame, bool]]:
    """Every CSV of the report, by file name: ``(table, write the index)``."""
    ident = rep.identifiability
    rows = [{"kind": "determined", "quantity": n, "weights": f"{n}: 1"} for n in ident.determined]
    rows += [{"kind": "combination", "quantity": c["name"],
              "weights": "; ".join(f"{k}: {v:.6g}" for k, v in c["weights"].items())} for c in rep.combinations]
    rows += [{"kind": "undetermined", "quantity": n, "weights": f"{n}: 1"} for n in ident.undetermined]
    out = {"summary.csv": (summary_table(rep), True),
           "identifiability.csv": (pd.DataFrame(rows, columns=["kind", "quantity", "weights"]), False),
           "combinations.csv": (pd.DataFrame(rep.combinations).drop(columns="weights", errors="ignore"), False),
           "least_squares.csv": (ls.table, False),
           "diagnostics.csv": (mcmc_plots.diagnostics_table(rep.summary, rep.sampling), True),
           "priors.csv": (priors_table(rep.log_posterior), True),
           "budget.csv": (budget_table(rep.summary), True)}
    if campaign.truth is not None:
        out["truth.csv"] = (truth_table(rep, ls, campaign.truth), False)
    return out


def truth_table(rep, ls: LeastSquares, truth) -> pd.DataFrame:
    """The stated truth of a simulated campaign beside the posterior and the least squares, for every quantity the
    campaign determines (deviations one by one and combinations): ``z`` = (mean − truth) / sd, ``in_hdi``."""
    s = rep.summary
    value = {n: units.from_internal(v, s.loc[n, "unit"]) for n, v in truth.deviations.items() if n in s.index}
    items = [(n, {n: 1.0}, s.loc[n, "mean"], s.loc[n, "sd"], s.loc[n, "hdi_low"], s.loc[n, "hdi_high"])
             for n in rep.identifiability.determined]
    items += [(c["name"], c["weights"], c["mean"], c["sd"], c["hdi_low"], c["hdi_high"]) for c in rep.combinations]
    lsq = ls.table.set_index("quantity")
    rows = []
    for name, w, mean, sd, low, high in items:
        t = sum(v * value.get(k, 0.0) for k, v in w.items())
        rows.append({"quantity": name, "truth": t, "mean": mean, "sd": sd, "hdi_low": low, "hdi_high": high,
                     "in_hdi": bool(low <= t <= high), "z": (mean - t) / sd,
                     "least_squares": lsq.loc[name, "estimate"], "least_squares_u": lsq.loc[name, "u"]})
    return pd.DataFrame(rows)


def _page(rep, ls: LeastSquares, tables, *, campaign, tmp: Path, loo, shown) -> Page:
    """The report's page; ``shown``: the deviations its per-quantity figures are drawn for."""
    desc = campaign.machine.description
    post = rep.log_posterior
    ident = rep.identifiability
    page = Page(f"Bayesian calibration report — {desc.name or desc.configuration} ({desc.configuration})")
    page.paragraph("What the intervals rest on (share of each posterior variance by source; section 'Uncertainty "
                   "budget'): " + budget_plot.dominant_sentence(rep.summary, [n for n in rep.summary.index
                                                                            if n in post.space.names], post=post))
    page.box("missing", "Not in this report (sections of the thesis machine's)", NOT_MADE)
    page.box("warn", "Warnings", rep.warnings + rep.not_identified + rep.prior_notes)

    page.section("machine", "The machine")
    kind = f"built-in type {desc.builtin}" if desc.builtin else "described in the campaign"
    page.paragraph(f"{desc.name or 'The machine'}: configuration {desc.configuration} ({kind}; docs/machines.md), "
                   f"squareness in the {desc.squareness} form. Deviations estimated (ISO 230-7): "
                   f"{', '.join(n for n in post.space.names if n in rep.summary.index)}.")
    page.figure(tmp / "machine.png", CHAIN_CAPTION, "the machine's chain at the home pose")
    page.figure(tmp / "deviations.png", DEVIATIONS_CAPTION, "what each location error means")

    page.section("determined", "What this campaign determines")
    page.paragraph("Computed from the campaign's Jacobian at the home pose (deviations and nuisance terms; the T ball "
                   "taken as centred, as the thesis does): a deviation is determined when no direction the data "
                   "cannot see moves it, only in combination when such a direction moves it together with others "
                   "(the combination named is what the data see), not at all when it moves alone — its posterior is "
                   "then its prior. identifiability.csv, combinations.csv.")
    page.box("statement", "Determined", [
        "one by one: " + (", ".join(ident.determined) or "none"),
        *[f"in combination: {c['name']} = {c['mean']:.2f} ± {c['sd']:.2f} {units.SYMBOL[c['unit']]} (95 % HDI "
          f"{c['hdi_low']:.2f} to {c['hdi_high']:.2f})" for c in rep.combinations],
        "not at all: " + (", ".join(ident.undetermined) or "none")])

    page.section("results", "Results")
    page.paragraph(f"Posterior of the deviations under the {post.model_name} model ({DATA_LABELS[post.data]}): "
                   "mean, sd and 95 % highest-density interval; angles in arc seconds, lengths in micrometres. "
                   "summary.csv.")
    s = rep.summary
    page.table(pd.DataFrame({"unit": s["unit"].map(units.SYMBOL), "mean": s["mean"], "sd": s["sd"],
                             "HDI 2.5 %": s["hdi_low"], "HDI 97.5 %": s["hdi_high"], "R-hat": s["r_hat"],
                             "identified by": s["identification"], "prior sensitivity": s["prior_sensitivity"]}),
               digits={"R-hat": 3})
    page.section("least-squares", "Least-squares identification beside the posterior")
    page.paragraph(f"The deterministic counterpart: the least-squares solution of the chain's first order, the "
                   f"nuisance terms held to their set-up knowledge, the deviations free, at σ_model = "
                   f"{ls.sigma_model_um:.2f} µm (the posterior median); only what the campaign determines. "
                   "least_squares.csv.")
    lsq = ls.table.set_index("quantity")
    post_mean = {**{n: (s.loc[n, "mean"], s.loc[n, "sd"]) for n in ident.determined},
                 **{c["name"]: (c["mean"], c["sd"]) for c in rep.combinations}}
    page.table(pd.DataFrame({"unit": lsq["unit"].map(units.SYMBOL), "least squares": lsq["estimate"],
                             "u": lsq["u"], "posterior mean": [post_mean[n][0] for n in lsq.index],
                             "posterior sd": [post_mean[n][1] for n in lsq.index]}))
    if "truth.csv" in tables:
        t = tables["truth.csv"][0]
        page.section("truth", "The stated truth of this simulated campaign")
        n_in = int(t["in_hdi"].sum())
        page.paragraph(f"{n_in} of {len(t)} determined quantities have their true value inside the 95 % HDI; z is "
                       "(posterior mean − truth) / posterior sd. truth.csv.")
        page.table(t.set_index("quantity"), digits=2)
    _statement_section(page, rep)
    _budget_section(page, rep, tmp, sigma_names=shown)
    page.section("corner", "Joint posterior of the determined deviations")
    page.figure(tmp / "corner.png", CORNER_CAPTION, "corner plot")
    page.figure(tmp / "forest.png", "95 % HDI of every deviation (an undetermined one spans its prior).",
                "forest plot")
    if "ppc.csv" in tables:
        ppc_df = tables["ppc.csv"][0]
        page.section("ppc", "Posterior predictive check")
        page.figure(tmp / "ppc.png", ppc.CAPTION, "posterior predictive check")
        page.paragraph(f"{int((~ppc_df['inside_95']).sum())} of {len(ppc_df)} observed ball-bar means fall outside "
                       "their 95 % predictive interval. ppc.csv.")
    page.section("loo", "Leave-one-out consistency")
    page.paragraph("Does each measurement agree with what all the others predict for it? " + loo.power_sentence()
                   + " loo.csv.")
    page.box("warn", "Leave-one-out: measurements the others do not predict", loo.outlier_sentences())
    page.figure(tmp / "loo.png", loo_plot.CAPTION, "leave-one-out elpd and Pareto k per observation")
    page.section("priors", "Priors")
    page.table(priors_table(post))
    page.section("diagnostics", "Sampler diagnostics")
    page.paragraph(sampler_paragraph(rep))
    diag = tables["diagnostics.csv"][0]
    page.table(diag.assign(ess_bulk=diag["ess_bulk"].round().astype(int),
                           ess_tail=diag["ess_tail"].round().astype(int)), digits={"r_hat": 3, "tau_steps": 0})
    page.figure(tmp / "rank.png", mcmc_plots.RANK_CAPTION, "rank plots")
    page.figure(tmp / "trace.png", mcmc_plots.TRACE_CAPTION, "trace plots")
    return page
