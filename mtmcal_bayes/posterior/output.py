"""Text and JSON of a posterior, for the console and the report."""

from __future__ import annotations

import math

from .. import units
from .checks import thesis_assumption_effect

#: summary columns of the JSON (SPEC §10)
JSON_COLUMNS = ["mean", "sd", "median", "hdi_low", "hdi_high", "r_hat", "ess_bulk", "ess_tail", "unit"]


def posterior_json(result) -> dict:
    """JSON of a :class:`~mtmcal_bayes.posterior.PosteriorResult`: summary and comparison per quantity,
    diagnostics."""
    post = result.log_posterior
    return {
        "model": post.model_name, "data": post.data, "campaign": post.campaign.source, "fix_dx_BT": post.fix_dx_BT,
        "summary": {n: {c: (row[c] if c == "unit" else float(row[c])) for c in JSON_COLUMNS}
                    for n, row in result.summary.iterrows()},
        "comparison": {n: {k: (None if v is None or (isinstance(v, float) and math.isnan(v)) else v)
                           for k, v in row.items()} for n, row in result.comparison.iterrows()},
        "diagnostics": result.diagnostics.to_json(),
    }


def format_posterior(result) -> str:
    """Human-readable posterior summary, comparison with the deterministic results, diagnostics."""
    r = result.sampling
    s = result.summary
    data = {"ballbar": "", "probe": ", touch-probe data", "both": ", ball-bar and touch-probe data"}[result.data]
    lines = [f"Posterior, model {result.model}{data} ({r.chains.shape[0]} ensembles × {r.chains.shape[2]} walkers, "
             f"{r.n_steps} steps, {r.wall_time:.0f} s); 95 % HDI"]
    hdr = f"{'quantity':18s} {'unit':>4s} {'mean':>9s} {'sd':>7s} {'95 % HDI':>20s} {'R-hat':>6s} {'ESS':>7s}  ball bar  probe(thesis)"
    lines.append(hdr)
    c = result.comparison
    for name, row in s.iterrows():
        line = (f"{name:18s} {units.SYMBOL[row['unit']]:>4s} {row['mean']:9.2f} {row['sd']:7.2f} "
                f"[{row['hdi_low']:8.2f}, {row['hdi_high']:8.2f}] {row['r_hat']:6.3f} {row['ess_bulk']:7.0f}")
        if name in c.index:
            ref = c.loc[name]
            bb = ref["ballbar"]
            line += f"  {bb:8.2f}{'' if ref['ballbar_in_hdi'] else '*'}" if bb is not None and bb == bb else "         —"
            pr = ref["probe_reported"]
            line += f"  {pr:8.2f}{'' if ref['probe_reported_in_hdi'] else '*'}" if pr is not None and pr == pr else "        —"
        lines.append(line)
    lines.append("* = outside the 95 % HDI")
    if result.not_identified:
        lines += ["", "Not identified by the data:"] + [f"  - {m}" for m in result.not_identified]
    d = result.diagnostics
    lines += ["", f"Diagnostics: converged {d.converged}, τ_max {d.tau_max_steps:.1f} steps, burn-in "
              f"{d.burn_in}, min bulk / tail ESS {d.min_ess_bulk:.0f} / {d.min_ess_tail:.0f} (target "
              f"{d.target_ess:g}; {d.ess_bulk_per_second:.0f}/s), max R-hat {d.max_r_hat:.3f}"
              + (f", independence proposals accepted {100 * d.independence_acceptance:.0f} %"
                 if d.independence_acceptance == d.independence_acceptance else "")]
    if result.reference is not None:
        lines.append(f"Accuracy {result.reference.sentence()}")
    return "\n".join(lines)


def format_sample(result) -> str:
    """What ``sample`` prints: :func:`format_posterior` and, unless imposed, the effect of dx_BT = 0."""
    lines = [format_posterior(result)]
    post = result.log_posterior
    if not post.fix_dx_BT:
        sigma_um = float(result.summary.loc["sigma_model", "median"])
        lines += ["", f"The thesis assumption dx_BT = 0 (Eq 4.2), closed form at sigma_model = {sigma_um:.2f} µm "
                  "(the posterior median; fix_dx_BT, on the command line --fix-dx-BT, samples it):",
                  thesis_assumption_effect(post.campaign, post.model_name, sigma_um, post.data).round(2).to_string()]
    if result.output:
        lines += ["", f"posterior written to {result.output} (ArviZ InferenceData, NetCDF)"]
    return "\n".join(lines)
