"""Text and files of a simulation-based calibration run."""

from __future__ import annotations

import json
from pathlib import Path

from ..figure_style import save_png
from ..io.textfiles import atomic_directory
from .criteria import INTERVALS, P_MIN
from .figures import ecdf_differences, rank_histograms


def format_sbc(result) -> str:
    """Table of p-values and coverages per quantity, with the verdict."""
    s, j = result.summary(), result.document()
    st = result.settings
    lo, hi = j["coverage_90_band"]
    lines = [(f"Simulation-based calibration: {st.model} model, {st.sampler} sampler, N = {j['n']} replicates, "
             f"L = {st.n_ranked} ranked draws, seed {st.seed}, {st.workers} worker(s)"),
             f"  wall time {result.wall_time:.0f} s; median {j['replicate_seconds_median']:.1f} s per replicate"]
    if st.sampler == "emcee":
        lines.append(f"  production sampler, step budget {st.max_steps} per ensemble; {j['replicates_not_converged']} "
                     f"of {j['n']} replicates stopped at the budget before the ESS and R-hat targets")
    width = max([18] + [len(q) for q in result.quantities])  # a described machine's combinations are longer
    head = (f"{'quantity':{width}s} {'p_uniform':>9s} " + " ".join(f"{f'cov{round(100 * p)}':>6s}" for p in INTERVALS)
            + f" {'z mean':>7s} {'z sd':>5s} {'contraction':>11s}  verdict")
    lines += ["", head]
    for q, r in s.iterrows():
        cov = " ".join(f"{100 * r[f'coverage_{round(100 * p)}']:5.1f}%" for p in INTERVALS)
        verdict = "ok" if r["ok"] else "FAIL"
        lines.append(f"{q:{width}s} {r['p_uniform']:9.3f} {cov} {r['z_mean']:7.2f} {r['z_sd']:5.2f} "
                     f"{r['contraction']:11.3f}  {verdict}")
    lines += ["", (f"A quantity passes when its ranks pass the χ² uniformity test (p > {j['p_min']:.2g}) and its 90 % "
              f"HDI covers the truth in {100 * lo:.2f}–{100 * hi:.2f} % of the replicates (the central "
              f"{100 * (1 - j['p_min']):.2f} % binomial range for N = {j['n']}): each of the {j['family']} quantities "
              f"the verdict is over is tested at {100 * P_MIN:g} % / {j['family']}, so a calibrated posterior fails "
              f"the verdict in at most {200 * P_MIN:g} % of runs."),
              *_checked_lines(result),
              "Verdict: " + (f"the posterior of the {_count(result)} quantities is calibrated." if j["all_ok"] else
                             "MISCALIBRATED: " + ", ".join(q for q in result.identified if not s.loc[q, "ok"]) + ".")]
    return "\n".join(lines)


def _count(result) -> str:
    """"n identified": the quantities the verdict is over ("eight" where that is not known: Table 4.5's)."""
    if result.identifiability is None:
        return "eight"
    return f"{len(result.identified)} identified"


def _plural(n: int, word: str) -> str:
    return f"{n} {word}" + ("" if n == 1 else "s")


def _checked_lines(result) -> list[str]:
    """What the rows are, and what is not checked."""
    if result.identifiability is None:
        return [("The first eight are the quantities of thesis Table 4.5; the rest are the other sampled deviations "
                 "and sigma_model.")]
    ident = result.identifiability
    one_by_one = len(result.identified) - len(ident.combinations)  # reported quantities, derived ones included
    what = f"the {one_by_one} quantit{'y' if one_by_one == 1 else 'ies'} this campaign determines one by one"
    if ident.combinations:
        what += (f" and its {_plural(len(ident.combinations), 'identifiable combination')} (Σ w·θ, display "
                 "units)")
    scales = [q for q in result.quantities if q not in result.identified]
    lines = [f"Checked: {what}, as its Jacobian says (the T ball centred: docs/machines.md); the verdict is over "
             f"these {len(result.identified)}" + (f", {' and '.join(scales)} shown beside them." if scales else ".")]
    if ident.undetermined:
        lines.append(f"Not checked: {', '.join(ident.undetermined)} — the campaign does not determine them: their "
                     "posterior is their prior.")
    return lines


def write_sbc(result, out_dir) -> list[str]:
    """sbc.json, sbc_summary.csv, sbc_replicates.csv, sbc_ranks.png, sbc_ecdf.png into ``out_dir``."""
    with atomic_directory(Path(out_dir)) as tmp:
        (tmp / "sbc.json").write_text(json.dumps(result.document(), indent=2, ensure_ascii=False), encoding="utf-8")
        result.summary().to_csv(tmp / "sbc_summary.csv", float_format="%.6g", index_label="quantity")
        result.replicates().to_csv(tmp / "sbc_replicates.csv", index=False, float_format="%.6g")
        save_png(rank_histograms(result), tmp / "sbc_ranks.png")
        save_png(ecdf_differences(result), tmp / "sbc_ecdf.png")
        files = sorted(p.name for p in tmp.iterdir())
    return files
