"""pandas tables of results, shared by the command line and the report."""

from __future__ import annotations

import pandas as pd

from . import units
from .identify import Identified, IdentificationResult


def identification_table(values: dict[str, Identified]) -> pd.DataFrame:
    """One row per quantity: recomputed and published value (display units), difference, flag."""
    rows = []
    for name, ident in values.items():
        if ident.reproduced is None:
            flag = "not computed: " + ident.missing if ident.missing else ("no published value" if ident.reported is None else "")
        else:
            flag = "reproduced" if ident.reproduced else "NOT REPRODUCED"
        rows.append({
            "quantity": name,
            "unit": units.SYMBOL[ident.unit],
            "recomputed": "—" if ident.display is None else f"{ident.display:.2f}",
            "thesis": "—" if ident.reported is None else f"{ident.reported_display:.{ident.reported.decimals}f}",
            "difference": "—" if ident.difference is None else f"{ident.difference:+.3f}",
            "Eq": ident.equation,
            "status": flag,
            "note": ident.note or "",
        })
    return pd.DataFrame(rows)


def to_text(df: pd.DataFrame) -> str:
    """Plain-text table with text columns left-aligned."""
    left = {c: (lambda w: (lambda v: f"{v:<{w}}"))(max(len(c), df[c].astype(str).str.len().max()))
            for c in ("quantity", "status", "note") if c in df}
    header = {c: c.ljust(max(len(c), df[c].astype(str).str.len().max())) for c in left}
    return df.rename(columns=header).to_string(index=False, formatters={header[c]: f for c, f in left.items()})


def format_identification(result: IdentificationResult) -> str:
    """Human-readable text of :func:`~mtmcal_bayes.identify.identify` results."""
    out = [f"Campaign: {result.source}", "",
           "Ball bar, thesis Eqs 4.10–4.18 on the means of the repeats, beside [reported.ballbar] (thesis: Table 4.5)"]
    out.append(to_text(identification_table(result.ballbar)))
    out += ["", "Touch probe, thesis Eqs 5.1–5.19, beside [reported.probe] (thesis: Table 5.3)"]
    if result.probe:
        out.append(to_text(identification_table(result.probe)))
    else:
        out.append("  (no probe data in this campaign)")
    if result.checks:
        out += ["", "Checks the deterministic method leaves out:"] + [f"  - {c}" for c in result.checks]
    if result.assumptions:
        out += ["", "Assumptions:"] + [f"  - {a}" for a in result.assumptions]
    return "\n".join(out)


def format_posterior(rep, model: str) -> str:
    """Human-readable posterior summary, comparison with the deterministic results, diagnostics."""

    s = rep.summary
    lines = [f"Posterior, model {model} ({rep.result.chains.shape[0]} ensembles × {rep.result.chains.shape[2]} walkers, "
             f"{rep.result.n_steps} steps, {rep.result.wall_time:.0f} s); 95 % HDI"]
    hdr = f"{'quantity':18s} {'unit':>4s} {'mean':>9s} {'sd':>7s} {'95 % HDI':>20s} {'R-hat':>6s} {'ESS':>7s}  ball bar  probe(thesis)"
    lines.append(hdr)
    c = rep.comparison
    for name, r in s.iterrows():
        line = (f"{name:18s} {units.SYMBOL[r['unit']]:>4s} {r['mean']:9.2f} {r['sd']:7.2f} "
                f"[{r['hdi_low']:8.2f}, {r['hdi_high']:8.2f}] {r['r_hat']:6.3f} {r['ess_bulk']:7.0f}")
        if name in c.index:
            row = c.loc[name]
            bb = row["ballbar"]
            line += f"  {bb:8.2f}{'' if row['ballbar_in_hdi'] else '*'}" if bb is not None and bb == bb else "         —"
            pr = row["probe_reported"]
            line += f"  {pr:8.2f}{'' if row['probe_reported_in_hdi'] else '*'}" if pr is not None and pr == pr else "        —"
        lines.append(line)
    lines.append("* = outside the 95 % HDI")
    if rep.not_identified:
        lines += ["", "Not identified by the data:"] + [f"  - {m}" for m in rep.not_identified]
    d = rep.diagnostics()
    lines += ["", f"Diagnostics: converged {d['converged']}, τ_max {d['tau_max_steps']:.0f} steps, burn-in "
              f"{d['burn_in']}, min bulk ESS {d['min_ess_bulk']:.0f} ({d['ess_bulk_per_second']:.0f}/s), "
              f"max R-hat {d['max_r_hat']:.3f}"]
    return "\n".join(lines)
