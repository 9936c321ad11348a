"""The same campaign under every forward model its machine offers: intervals and predictive fit side by side (SPEC §9)."""

from __future__ import annotations

import pandas as pd

from .ppc import ppc_table

CAPTION_FOREST = (
    "Model-form uncertainty: 95 % HDIs of each quantity when the same measurements are interpreted with each "
    "forward model the machine offers (docs/model.md): on the thesis machine its linear relations (linear), the "
    "literal homogeneous-transform model of Eq 2.10 (htm-literal), the HTM model with pivots that reproduce the "
    "thesis relations (htm-thesis) and the chain; on a machine described by its chain, the chain's first order "
    "(linear) and the chain itself. Where the bars do not overlap, the choice of model matters more than the "
    "measurement noise."
)
CAPTION_PPC = (
    "Posterior predictive fit of every eccentricity under each model (50 %/95 % intervals, one colour per model) "
    "with the observed repeats; right: standardised residuals. A model that cannot reproduce a measurement "
    "shows |z| > 2 there."
)


def model_comparison_table(reports: dict, names) -> pd.DataFrame:
    """Long table: one row per (quantity of ``names``, model) with mean, sd, 95 % HDI, R-hat and bulk ESS."""
    rows = []
    for model, rep in reports.items():
        for name in names:
            if name in rep.summary.index:
                r = rep.summary.loc[name]
                rows.append({"quantity": name, "model": model, "unit": r["unit"], "mean": r["mean"], "sd": r["sd"],
                             "hdi_low": r["hdi_low"], "hdi_high": r["hdi_high"], "r_hat": r["r_hat"],
                             "ess_bulk": r["ess_bulk"]})
    return pd.DataFrame(rows)


def model_fit_table(reports: dict, campaign) -> pd.DataFrame:
    """Per model: rms and largest |z| of the observations, how many fall outside their 95 % predictive interval."""
    rows = []
    for model, rep in reports.items():
        t = ppc_table(rep.idata, campaign)
        rows.append({"model": model, "rms_z": float((t["z"] ** 2).mean() ** 0.5), "max_abs_z": float(t["z"].abs().max()),
                     "outside_95": int((~t["inside_95"]).sum()), "n_observations": len(t),
                     "sigma_model_median_um": rep.sigma_model_um})
    return pd.DataFrame(rows).set_index("model")


def disagreements(reports: dict, names) -> list[str]:
    """Quantities of ``names`` whose 95 % HDIs under two models do not overlap, as sentences."""
    out = []
    models = list(reports)
    for name in names:
        for i, a in enumerate(models):
            for b in models[i + 1:]:
                ra, rb = reports[a].summary.loc[name], reports[b].summary.loc[name]
                if ra["hdi_high"] < rb["hdi_low"] or rb["hdi_high"] < ra["hdi_low"]:
                    unit = "″" if ra["unit"] == "arcsec" else "µm"
                    out.append(f"{name}: {a} {ra['mean']:.1f} ± {ra['sd']:.1f} {unit} against {b} "
                               f"{rb['mean']:.1f} ± {rb['sd']:.1f} {unit} (95 % HDIs do not overlap)")
    return out
