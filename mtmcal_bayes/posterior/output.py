"""Text and JSON of a posterior, for the console and the report."""

from __future__ import annotations

import math

from .. import units
from ..inference import reading_choice
from ..inference.budget import sigma_prior_sentence, sigma_prior_sources
from ..machines.plugins import provided

#: summary columns of the JSON (SPEC §10)
JSON_COLUMNS = ["mean", "sd", "median", "hdi_low", "hdi_high", "r_hat", "ess_bulk", "ess_tail", "unit"]


def _num(v):
    """A JSON number, or None for None/NaN."""
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return None
    return v if isinstance(v, (bool, str)) else float(v)


def quantity_json(name: str, row, conformity=None) -> dict:
    """One quantity's entry of the JSON summary: the SPEC §10 columns, its ISO 230-7 symbol, the GUM statement
    (``u``, both 95 % coverage intervals, ``U`` and ``k`` or null with ``U_note`` saying why), its
    identifiability and, with a tolerance, the conformity decision (docs/metrology.md)."""
    out = {c: (row[c] if c == "unit" else float(row[c])) for c in JSON_COLUMNS}
    through = row.get("identified_through")
    out.update({
        "iso": row.get("iso") if isinstance(row.get("iso"), str) else None,
        "u": _num(row["u"]),
        "ci95_shortest": [_num(row["ci95_shortest_low"]), _num(row["ci95_shortest_high"])],
        "ci95_symmetric": [_num(row["ci95_symmetric_low"]), _num(row["ci95_symmetric_high"])],
        "coverage_probability": _num(row["coverage_probability"]), "U": _num(row["U"]), "k": _num(row["k"]),
        "U_note": row["U_note"] or None, "n_draws": int(row["n_draws"]),
        "endpoint_tolerance": _num(row["endpoint_tolerance"]), "significant_digits": int(row["significant_digits"]),
        "identified": row["identified"] if isinstance(row["identified"], bool) else None,
        "identification": row["identification"] if isinstance(row["identification"], str) else None,
        "combination": row["combination"].split("; ") if isinstance(row.get("combination"), str) else [],
        "identified_through": through.split(", ") if isinstance(through, str) and through else [],
        "prior_growth": _num(row["prior_growth"]), "nuisance_growth": _num(row["nuisance_growth"]),
        "prior_sensitivity": row.get("prior_sensitivity") or None,
    })
    budget = {k.split(":", 1)[1]: float(v) for k, v in row.items() if k.startswith("budget:") and v == v}
    if budget:
        out["budget"] = budget
    if _num(row.get(reading_choice.ALTERNATIVE)) is not None:  # the campaign's reading of some runs was a choice
        out["reading_choice"] = {"rests_on_choice": reading_choice.rests(row),
                                 "alternative_mean": _num(row[reading_choice.ALTERNATIVE]),
                                 "shift_sd": _num(row[reading_choice.SHIFT])}
    if conformity is not None and name in conformity.index:
        c = conformity.loc[name]
        out.update({"tolerance": {"low": _num(c["tolerance_low"]), "high": _num(c["tolerance_high"])},
                    "p_nonconformance": _num(c["p_nonconformance"]), "conformity": c["conformity"],
                    "acceptance_zone": [_num(c["acceptance_low"]), _num(c["acceptance_high"])]})
        if c.get("next_measurement") is not None and isinstance(c.get("next_measurement"), str):
            out["next_measurement"] = {"name": c["next_measurement"], "sd_after": _num(c["sd_after"]),
                                       "sd_to_decide": _num(c["sd_to_decide"]), "would_decide": c["would_decide"]}
    return out


def posterior_json(result) -> dict:
    """JSON of a :class:`~mtmcal_bayes.posterior.PosteriorResult`: summary and comparison per quantity,
    diagnostics; ``sigma_model_prior``: each sampled scale's prior and whether it was assumed or learnt (and from
    what)."""
    post = result.log_posterior
    return {
        "model": post.model_name, "data": post.data, "campaign": post.campaign.source, "fix_dx_BT": post.fix_dx_BT,
        "sigma_model_prior": sigma_prior_sources(post),
        "summary": {n: quantity_json(n, row, result.conformity) for n, row in result.summary.iterrows()},
        "comparison": {n: {k: (None if v is None or (isinstance(v, float) and math.isnan(v)) else v)
                           for k, v in row.items()} for n, row in result.comparison.iterrows()},
        "diagnostics": result.diagnostics.to_json(),
        **choice_json(result.summary, post.campaign),
        "identifiability": result.identifiability.as_dict(), "combinations": result.combinations,
    }


def choice_json(summary, campaign) -> dict:
    """``{"reading_choice": {...}}`` where the campaign's reading of some ball-bar runs was a choice: the mark, what
    it means, the runs with their chosen and alternative readings, why, and the quantities that rest on it; ``{}``
    otherwise."""
    if not reading_choice.has_choice(summary):
        return {}
    bb = campaign.ballbar
    return {"reading_choice": {
        "mark": reading_choice.MARK, "note": reading_choice.note(campaign), "reason": bb.alternative_reason or None,
        "runs": [{"run": r.label, "convention": r.convention or bb.convention, "alternative_convention":
                  r.alternative_convention} for r in bb.reading_choices()],
        "rests_on_choice": reading_choice.marked(summary)}}


def format_posterior(result) -> str:
    """Human-readable posterior summary, comparison with the deterministic results, diagnostics."""
    r = result.sampling
    s = result.summary
    data = {"ballbar": "", "probe": ", touch-probe data", "both": ", ball-bar and touch-probe data"}.get(
        result.data, f", {result.data} data")
    lines = [f"Posterior, model {result.model}{data} ({r.chains.shape[0]} ensembles × {r.chains.shape[2]} walkers, "
             f"{r.n_steps} steps, {r.wall_time:.0f} s); 95 % HDI"]
    choice = reading_choice.has_choice(s)
    c = result.comparison
    # the deterministic values beside the posterior, where the campaign has any (the thesis' published methods)
    refs = any(c[k].notna().any() for k in ("ballbar", "probe_reported") if k in c.columns)
    hdr = (f"{'quantity':18s} {'ISO 230-7':10s} {'unit':>4s} {'mean':>9s} {'sd':>7s} {'95 % HDI':>20s} {'R-hat':>6s} "
           f"{'ESS':>7s}" + ("  ball bar  probe(thesis)" if refs else ""))
    width = len(hdr)
    hdr += f"  {reading_choice.HEAD:>16s}" if choice else ""
    lines.append(hdr)
    for name, row in s.iterrows():
        iso = row["iso"] if isinstance(row["iso"], str) else "—"
        line = (f"{name:18s} {iso:10s} {units.SYMBOL[row['unit']]:>4s} {row['mean']:9.2f} {row['sd']:7.2f} "
                f"[{row['hdi_low']:8.2f}, {row['hdi_high']:8.2f}] {row['r_hat']:6.3f} {row['ess_bulk']:7.0f}")
        if refs and name in c.index:
            ref = c.loc[name]
            bb = ref["ballbar"]
            line += f"  {bb:8.2f}{'' if ref['ballbar_in_hdi'] else '*'}" if bb is not None and bb == bb else "         —"
            pr = ref["probe_reported"]
            line += f"  {pr:8.2f}{'' if ref['probe_reported_in_hdi'] else '*'}" if pr is not None and pr == pr else "        —"
        if choice and reading_choice.rests(row):
            line = f"{line:{width}s}  {reading_choice.mark_cell(row):>16s}"
        lines.append(line)
    lines += ["* = outside the 95 % HDI"] if refs else []
    if choice:
        lines.append(result.reading_choice_note)
    lines += ["", gum_block(s), "", budget_block(s, result)]
    if result.conformity is not None and not result.conformity.empty:
        lines += ["", conformity_block(result.conformity, s)]
    if result.not_identified:
        lines += ["", "Identifiability (the campaign's Jacobian, nuisance terms included):"] + [
            f"  - {m}" for m in result.not_identified]
    if result.prior_notes:
        lines += ["", "Prior sensitivity (closed form; a diagnostic, it does not decide what is identified):"] + [
            f"  - {m}" for m in result.prior_notes]
    d = result.diagnostics
    lines += ["", f"Diagnostics: converged {d.converged}, τ_max {d.tau_max_steps:.1f} steps, burn-in "
              f"{d.burn_in}, min bulk / tail ESS {d.min_ess_bulk:.0f} / {d.min_ess_tail:.0f} (target "
              f"{d.target_ess:g}; {d.ess_bulk_per_second:.0f}/s), max R-hat {d.max_r_hat:.3f}"
              + (f", independence proposals accepted {100 * d.independence_acceptance:.0f} %"
                 if d.independence_acceptance == d.independence_acceptance else "")]
    if result.reference is not None:
        lines.append(f"Accuracy {result.reference.sentence()}")
    return "\n".join(lines)


def gum_block(s) -> str:
    """The GUM statement of every quantity as a console table (docs/metrology.md)."""
    n = int(s["n_draws"].iloc[0])
    choice = reading_choice.has_choice(s)
    lines = [f"Uncertainty statement (GUM-S1, {n:,} posterior draws; coverage probability 95 %; U = k·u only where "
             "the posterior is close to Gaussian)",
             f"{'quantity':18s} {'unit':>4s} {'estimate':>9s} {'u':>7s} {'shortest 95 %':>20s} {'symmetric 95 %':>20s} "
             f"{'U (k)':>13s} {'endpoints ±':>11s}" + (f"  {reading_choice.HEAD:>16s}" if choice else "")]
    for name, r in s.iterrows():
        U = f"{r['U']:.2f} ({r['k']:.2f})" if isinstance(r["U"], float) and r["U"] == r["U"] else "not stated"
        lines.append(f"{name:18s} {units.SYMBOL[r['unit']]:>4s} {r['mean']:9.2f} {r['u']:7.2f} "
                     f"[{r['ci95_shortest_low']:8.2f}, {r['ci95_shortest_high']:8.2f}] "
                     f"[{r['ci95_symmetric_low']:8.2f}, {r['ci95_symmetric_high']:8.2f}] {U:>13s} "
                     f"{r['endpoint_tolerance']:11.2g}" + (f"  {reading_choice.mark_cell(r):>16s}"
                                                            if choice and reading_choice.rests(r) else ""))
    lines.append(("U not stated: y ± 1.96u differs from the symmetric interval by more than the numerical "
                  "tolerance (JSON: U_note); " if s["U"].isna().any() else "") + "endpoints ± = 2 Monte-Carlo standard errors")
    if choice:
        lines.append(reading_choice.short_note())
    return "\n".join(lines)


#: short column heads of the budget table
BUDGET_HEADS = {"repeatability": "repeat", "instrument": "instr.", "probe readings": "probe", "sigma_model": "σ_model",
                "sigma_model_probe": "σ_probe", "R-test readings": "R-test", "sigma_model_rtest": "σ_rtest",
                "prior:R-test zero": "R zero", "prior:R-test sphere placement": "R sphere",
                "prior:R-test nest centring": "R nest", "prior:R-test nest length": "R length",
                "sigma_model_uncertainty": "σ unknown", "prior:deviations": "dev.prior", "prior:T-ball centring": "T-ball",
                "prior:dRB": "dRB", "prior:W-ball clamping": "W-ball", "prior:stylus centring": "stylus",
                "prior:dRS": "dRS", "prior:rS": "rS", "prior:sphere placement": "sphere", "prior:reading datum": "datum"}


def budget_block(s, result) -> str:
    """The uncertainty budget as a console table: % of each quantity's posterior variance by source."""
    cols = [c for c in s.columns if c.startswith("budget:") and (s[c].fillna(0) >= 0.005).any()]
    post = result.log_posterior
    scales = " and ".join(post.scales)
    how = (f"{scales} fixed at {units.from_internal(post.fixed_sigma, 'um'):g} µm" if post.fixed_sigma is not None
           else f"averaged over the posterior of {scales}, law of total variance")
    lin = "" if post.model_name == "linear" else f"; {post.model_name} linearised at the posterior mean"
    heads = [BUDGET_HEADS.get(c.split(":", 1)[1], c.split(":", 1)[1]) for c in cols]
    lines = [f"Uncertainty budget: % of each posterior variance by source ({how}{lin})"]
    lines += [sentence] if (sentence := sigma_prior_sentence(post)) else []
    lines.append(f"{'quantity':18s} " + " ".join(f"{h:>9s}" for h in heads))
    for name, r in s.iterrows():
        if r[cols].isna().all():
            continue
        lines.append(f"{name:18s} " + " ".join(f"{100 * r[c]:9.1f}" for c in cols))
    return "\n".join(lines)


def conformity_block(conf, s) -> str:
    """Tolerances, probabilities of nonconformance, ISO 14253-1 verdicts and the way to decide the undecided."""
    from .conformity import row_tolerance_text

    lines = ["Conformity (ISO 14253-1, guard bands = the 95 % coverage interval)",
             f"{'quantity':18s} {'ISO 230-7':10s} {'tolerance':>16s} {'P(nonconf.)':>11s}  verdict"]
    for name, r in conf.iterrows():
        row = s.loc[name]
        iso = row["iso"] if isinstance(row["iso"], str) else "—"
        lines.append(f"{name:18s} {iso:10s} {row_tolerance_text(r, row['unit']):>16s} {r['p_nonconformance']:11.3f}  "
                     f"{r['conformity']}")
        if isinstance(r.get("next_measurement"), str):
            sym = units.SYMBOL[row["unit"]]
            verdict = "it would decide" if r["would_decide"] else "not enough on its own"
            lines.append(f"{'':30s}next measurement: {r['next_measurement']} would bring its sd from {row['sd']:.2g} "
                         f"to {r['sd_after']:.2g} {sym}; deciding needs < {r['sd_to_decide']:.2g} {sym} if the "
                         f"estimate stays: {verdict} (mtmcal-bayes plan --target {name})")
    return "\n".join(lines)


def identifiability_block(ident, combinations: list[dict]) -> str:
    """What the campaign determines (a described machine's, computed from its Jacobian): console lines."""
    lines = ["What this campaign determines (from its Jacobian, the T ball centred: docs/machines.md)"]
    lines.append("  one by one:     " + (", ".join(ident.determined) or "none"))
    for c in combinations:
        lines.append(f"  in combination: {c['name']} = {c['mean']:.2f} ± {c['sd']:.2f} {units.SYMBOL[c['unit']]} "
                     f"(95 % HDI {c['hdi_low']:.2f} to {c['hdi_high']:.2f})")
    lines.append("  not at all:     " + (", ".join(ident.undetermined) or "none") +
                 ("  (their width is set by priors)" if ident.undetermined else ""))
    return "\n".join(lines)


def format_sample(result) -> str:
    """What ``sample`` prints: :func:`format_posterior`, the identifiability and what the machine's plug-in adds
    (the thesis': unless imposed, the effect of dx_BT = 0)."""
    lines = [format_posterior(result)]
    post = result.log_posterior
    if result.identifiability is not None:
        lines += ["", identifiability_block(result.identifiability, result.combinations)]
    notes = provided(post.campaign.machine, "sample_notes")  # what a plug-in adds (the thesis': dx_BT = 0)
    if notes is not None:
        lines += notes(result)
    if result.output:
        lines += ["", f"posterior written to {result.output} (ArviZ InferenceData, NetCDF)"]
    return "\n".join(lines)


