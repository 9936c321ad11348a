"""Text and files of a measurement plan."""

from __future__ import annotations

import json
from pathlib import Path

import pandas as pd

from .. import units
from ..figure_style import save_png
from ..io.textfiles import atomic_directory
from .figures import ranking_figure, sweep_figure

SHOWN = 15
#: patterns shown in "What would teach sigma_model" (the best candidate of each)
SIGMA_SHOWN = 6
#: R-test candidates listed with their minutes
RTEST_SHOWN = 5


def format_plan(result) -> str:
    """Human-readable ranking, sweep summary and Monte-Carlo check of a :class:`~.plan.PlanResult`."""
    sym = [units.SYMBOL[u] for u in result.target_units]
    t = result.table
    lines = [f"Candidate measurements for {', '.join(result.targets)}, best first "
             f"(closed form, {result.model} model, sigma_model {result.sigma_model_um:.2f} µm)"]
    head = f"{'#':>3s}  {'candidate':34s} {'EIG bits':>8s}  " + "  ".join(
        f"{tg + ' ' + s_:>22s}" for tg, s_ in zip(result.targets[:3], sym)) + "  verdict"
    lines.append(head)
    for _, r in t.head(SHOWN).iterrows():
        sds = "  ".join(f"{r[f'{tg} sd_before']:9.3g} → {r[f'{tg} sd_after']:9.3g}" for tg in result.targets[:3])
        new = f" (identifies {r['newly_identified']})" if r["newly_identified"] else ""
        lines.append(f"{int(r['rank']):3d}  {r['name'][:34]:34s} {r['eig_bits']:8.3f}  {sds}  {r['verdict']}{new}")
    rest = t.iloc[SHOWN:]
    if len(rest):
        lines.append(f"  … {len(rest)} more ({int((~rest['feasible']).sum())} infeasible, "
                     f"{int((rest['feasible'] & ~rest['informative']).sum())} identifying nothing new); all in "
                     "--json or -o DIR/plan.csv")
    bad = t[~t["feasible"]]
    for _, r in bad.iterrows():
        lines.append(f"  rejected: {r['name']}: {r['verdict']}")
    lines += rtest_lines(result)
    lines += sigma_lines(result)
    s = result.sweep
    if len(s):
        lines += ["", f"Sweep: {result.sweep_pattern} at the primary tool length plus Δ"]
    for tg, s_ in zip(result.targets, sym if len(s) else []):
        first, last = s.iloc[0], s.iloc[-1]
        not_id = s.loc[~s[f"{tg} identified"], "extension_mm"]
        msg = (f"  {tg}: sd {first[f'{tg} sd_before']:.3g}{s_} today; {first[f'{tg} sd_after']:.3g}{s_} at Δ = 0, "
               f"{s.loc[s['extension_mm'] == 50, f'{tg} sd_after'].iloc[0]:.3g}{s_} at 50 mm, "
               f"{s.loc[s['extension_mm'] == 150, f'{tg} sd_after'].iloc[0]:.3g}{s_} at 150 mm, "
               f"{last[f'{tg} sd_after']:.3g}{s_} at {last['extension_mm']:g} mm")
        if len(not_id):
            msg += f"; not identified for Δ ≤ {not_id.max():g} mm" if not_id.min() == 0 else \
                f"; not identified at Δ = {', '.join(f'{v:g}' for v in not_id)} mm"
        lines.append(msg)
    if len(result.check):
        lines += ["", "Monte-Carlo preposterior check (sigma_model learnt from simulated data, exact for the "
                  "linear model):"]
        for _, r in result.check.iterrows():
            lines.append(f"  {r['candidate'][:30]:30s} {r['target']:18s} closed form {r['sd_after_closed_form']:8.3g}"
                         f"  Monte Carlo {r['sd_after_monte_carlo']:8.3g}  ({100 * r['relative_difference']:+.1f} %)")
    lines += ["", "Notes:"] + [f"  - {n}" for n in result.notes]
    return "\n".join(lines)


def rtest_lines(result) -> list[str]:
    """The best R-test candidates with their machine minutes (the time model's), when the plan has any."""
    t = result.table
    r_t = t[t["kind"] == "rtest"]
    if not len(r_t):
        return []
    lines = ["", f"R-test candidates, best {min(RTEST_SHOWN, len(r_t))} of {len(r_t)} (machine minutes from the "
             "time model; plan.json gives each as its [[rtest.runs]] table, for ncgen --rtest once added):",
             f"  {'#':>3s}  {'candidate':40s} {'minutes':>7s}  {'EIG bits':>8s}  verdict"]
    for _, r in r_t.head(RTEST_SHOWN).iterrows():
        lines.append(f"  {int(r['rank']):3d}  {r['name'][:40]:40s} {r['minutes']:7.1f}  {r['eig_bits']:8.3f}  "
                     f"{r['verdict']}")
    return lines


def _runs(value, max_runs: int) -> str:
    if pd.isna(value):
        return f"not within {max_runs}"
    return "0 (met already)" if value == 0 else str(int(value))  # 0: met before any run (a learnt prior)


def sigma_lines(result) -> list[str]:
    """The "What would teach sigma_model" section: today's contraction, the best candidate of each pattern."""
    info, t = result.sigma_model, result.table
    if not info or "sigma_model_contraction" not in t:
        return []
    cap, target = info["max_runs"], info["target_contraction"]
    if info["evaluated_at_um"] == 0:
        return ["", "What would teach sigma_model: not computed at sigma_model = 0 (see the notes)"]
    ok = t[t["feasible"]].sort_values("sigma_model_rank")
    ref = info.get("contraction_reference")
    met = bool(ref) and info["contraction_now"] >= target
    learnt = f" learnt elsewhere, from {info['prior_source']['from']}" if ref else ""
    measure = (f"1 − posterior variance/that of the {ref['which']} prior {ref['prior']} (the wider)" if ref else
               "1 − posterior/prior variance")
    lines = ["", f"What would teach sigma_model (prior {info['prior']}{learnt}; closed form at "
             f"{info['evaluated_at_um']:.2f} µm; contraction = {measure}, Laplace approximation):",
             f"  today: {info['contraction_now']:.3f} from {info['means']} means"
             + (" — its posterior is almost its prior: the parameters absorb the residuals" if
                info["contraction_now"] < 0.1 and not ref else "")
             + (f" — {target:g} met already, with the learnt prior" if met else ""),
             f"  {'#':>3s}  {'candidate (best of its pattern)':34s} {'contraction':>11s}  runs to reach {target:g}"]
    for _, r in ok.drop_duplicates("pattern").head(SIGMA_SHOWN).iterrows():
        lines.append(f"  {int(r['sigma_model_rank']):3d}  {r['name'][:34]:34s} {r['sigma_model_contraction']:11.3f}  "
                     f"{_runs(r['sigma_model_runs_needed'], cap)}")
    if len(ok):
        best = ok.sort_values("rank").iloc[0]
        lines.append(f"  best for the targets, {best['name']}: {best['sigma_model_contraction']:.3f}, runs to reach "
                     f"{target:g}: {_runs(best['sigma_model_runs_needed'], cap)}")
    never = ok[ok["sigma_model_runs_needed"].isna()]
    if len(never):
        names = ", ".join(never["name"].head(4)) + (f" and {len(never) - 4} more" if len(never) > 4 else "")
        lines.append(f"  never within {cap} runs ({len(never)}): {names} — more repeats add no mean, and the means "
                     "of a run on a new W-ball placement go mostly into that placement's own offsets")
    return lines


def write_plan(result, out_dir) -> list[str]:
    """plan.csv, plan_sweep.csv, plan_check.csv, plan.json, plan_ranking.png, plan_sweep.png into ``out_dir``."""
    files = []
    with atomic_directory(Path(out_dir)) as tmp:
        result.table.to_csv(tmp / "plan.csv", index=False, float_format="%.6g")
        result.sweep.to_csv(tmp / "plan_sweep.csv", index=False, float_format="%.6g")
        result.check.to_csv(tmp / "plan_check.csv", index=False, float_format="%.6g")
        (tmp / "plan.json").write_text(json.dumps(result.document(), indent=2, ensure_ascii=False), encoding="utf-8")
        save_png(ranking_figure(result), tmp / "plan_ranking.png")
        if len(result.sweep):  # none without a ball-bar set-up
            save_png(sweep_figure(result), tmp / "plan_sweep.png")
        files = sorted(p.name for p in tmp.iterdir())
    return files
