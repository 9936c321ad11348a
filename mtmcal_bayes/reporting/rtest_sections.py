"""The report's R-test sections (docs/rtest.md, docs/report.md): per run its readings beside the posterior predictive
with the residuals and the R-test's discrepancy scale (``rtest.png``, ``rtest.csv``), and its nuisance terms with
their priors and posteriors (``rtest_terms.csv``).  Shown where the main posterior saw R-test readings, on every
machine alike."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.lines import Line2D

from .. import units
from ..figure_style import new_figure, tight_layout
from ..html_page import Page
from ..inference.results import observation_parts

#: the posterior predictive's variable of the R-test readings (inference/results.py)
VARIABLE = "rtest_reading"
#: each nuisance term's meaning, by its base name (docs/rtest.md, "The nuisance terms")
MEANING = {"xZR": "sensors' zero, X", "yZR": "sensors' zero, Y", "zZR": "sensors' zero, Z",
           "xPR": "sphere placement, X", "yPR": "sphere placement, Y", "zPR": "sphere placement, Z",
           "dLR": "nest length error (+ = longer)", "xNR": "nest centre offset, X", "yNR": "nest centre offset, Y",
           "zNR": "nest centre offset, Z"}
#: the owner of each kind of nuisance term, in words
OWNER = {"Z": "run", "P": "placement", "L": "nest", "N": "nest"}
#: the colour of each reading component
COMPONENT_COLOURS = {"X": "#0072B2", "Y": "#D55E00", "Z": "#009E73"}
CAPTION = ("R-test readings beside the posterior predictive, one row per run (its positions: the rotary axes' "
           "angles, °). Left: each component's observed mean of the repeats (X, Y, Z: markers) and the mean of its "
           "replicated value under the posterior (lines). Right: the residual, observed minus predictive mean "
           "(markers), beside the 95 % interval of the replicated mean about its mean (model prediction plus the "
           "readings' noise and the R-test's σ_model; bars, one scale for every run): a marker outside its bar is a "
           "reading the model cannot reproduce. z per reading: rtest.csv.")


def has_readings(rep) -> bool:
    """Whether the posterior ``rep`` saw R-test readings."""
    return VARIABLE in getattr(rep.idata, "posterior_predictive", {})


def readings_table(rep) -> pd.DataFrame:
    """rtest.csv: one row per reading (run, position, its angles, component): the observed mean of the repeats and
    their number, the posterior predictive's mean, sd and 95 % interval, the residual (observed − predictive mean)
    and z = residual / predictive sd, µm."""
    post = rep.log_posterior
    obs = next(o for var, o, _ in observation_parts(post.forward.observations) if var == VARIABLE)
    pp = np.asarray(rep.idata.posterior_predictive[VARIABLE]).reshape(-1, len(obs))
    lo, hi = np.quantile(pp, [0.025, 0.975], axis=0)
    mean, sd = pp.mean(axis=0), pp.std(axis=0)
    observed = units.from_internal(obs.mean, "um")
    runs = {run.id: run for run in post.campaign.rtest.runs}
    angles = [", ".join(f"{a} {v[k.position - 1]:g}" for a, v in runs[k.run].angles_deg.items()) for k in obs.keys]
    df = pd.DataFrame({"run": [k.run for k in obs.keys], "position": [k.position for k in obs.keys],
                       "angles_deg": angles, "component": [k.component for k in obs.keys],
                       "observed_mean_um": observed, "n_repeats": obs.n, "predictive_mean_um": mean,
                       "predictive_sd_um": sd, "predictive_2.5%_um": lo, "predictive_97.5%_um": hi,
                       "residual_um": observed - mean, "z": (observed - mean) / sd})
    df["inside_95"] = (observed >= lo) & (observed <= hi)
    return df


def terms_table(rep) -> pd.DataFrame:
    """rtest_terms.csv: the R-test's nuisance terms (each run's zero, each placement, each nest's length and
    offset), µm: owner, meaning, prior sd, posterior mean, sd and 95 % HDI, and the truth where the campaign states
    one."""
    from ..arviz_import import az

    post = rep.log_posterior
    priors = {p.name: p for p in post.priors.priors}
    truth = post.campaign.truth
    rows = []
    for p in post.space.parameters:
        if p.group != "rtest":
            continue
        draws = np.asarray(rep.idata.posterior[p.name]).reshape(-1)
        low, high = az.hdi(draws, hdi_prob=0.95)
        row = {"term": p.name, "owner": f"{OWNER[p.base[1]]} {p.owner}", "meaning": MEANING[p.base],
               "unit": "µm", "prior_sd": units.from_internal(priors[p.name].sd, "um"), "mean": draws.mean(),
               "sd": draws.std(), "hdi_low": low, "hdi_high": high}
        if truth is not None:
            row["truth"] = units.from_internal(truth.rtest.get(p.owner, {}).get(p.base, 0.0), "um")
        rows.append(row)
    return pd.DataFrame(rows)


def readings_figure(table: pd.DataFrame):
    """Per run (a row), the readings beside their predictive means, and the residuals beside the predictive
    intervals (:data:`CAPTION`)."""
    runs = list(dict.fromkeys(table["run"]))
    fig, axes = new_figure(len(runs), 2, figsize=(12, 2.3 * len(runs) + 0.9), squeeze=False,
                           gridspec_kw={"width_ratios": [1.6, 1.0]})
    offsets = dict(zip("XYZ", (-0.2, 0.0, 0.2)))
    reach = table[["residual_um"]].abs().max().max()
    reach = 1.1 * max(float(reach), float((table["predictive_97.5%_um"] - table["predictive_mean_um"]).max()))
    for (ax, res), run in zip(axes, runs):
        t = table[table["run"] == run]
        for comp, c in t.groupby("component", sort=False):
            colour = COMPONENT_COLOURS[comp]
            x = c["position"].to_numpy()
            ax.plot(x, c["predictive_mean_um"], "-", color=colour, lw=1.2, alpha=0.7)
            ax.plot(x, c["observed_mean_um"], "o", color=colour, ms=5, mfc="white", mew=1.5)
            xo = x + offsets[comp]
            res.vlines(xo, c["predictive_2.5%_um"] - c["predictive_mean_um"],
                       c["predictive_97.5%_um"] - c["predictive_mean_um"], color=colour, lw=4, alpha=0.3)
            res.plot(xo, c["residual_um"], "o", color=colour, ms=5, mfc="white", mew=1.5)
        first = t.drop_duplicates("position")
        ticks = [a.replace(", ", "\n") for a in first["angles_deg"]]
        ax.set_xticks(first["position"], ticks, fontsize=8)
        res.set_xticks(first["position"], ticks, fontsize=8)
        ax.set_title(f"run {run}", fontsize=10, loc="left")
        ax.set_ylabel("reading [µm]")
        res.set_ylabel("residual [µm]")
        res.set_ylim(-reach, reach)
        for a in (ax, res):
            a.axhline(0, color="0.6", lw=0.8, zorder=0)
            a.grid(axis="y", alpha=0.3)
    handles = [Line2D([], [], color=COMPONENT_COLOURS[c], marker="o", mfc="white", ls="-", label=c) for c in "XYZ"]
    handles += [Line2D([], [], color="0.5", marker="o", mfc="white", ls="none", label="observed mean"),
                Line2D([], [], color="0.5", lw=1.2, label="posterior predictive mean (left)"),
                Line2D([], [], color="0.5", lw=4, alpha=0.4, label="its 95 % interval (right)")]
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), fontsize=9, frameon=False)
    tight_layout(fig, (0, 0.45 / fig.get_figheight(), 1, 1))
    return fig


def rtest_section(page: Page, rep, readings: pd.DataFrame, terms: pd.DataFrame, *, tmp: Path) -> None:
    """The R-test's readings against the posterior predictive, its discrepancy scale and its nuisance terms."""
    s = rep.summary
    page.section("rtest", "R-test readings")
    n_out = int((~readings["inside_95"]).sum())
    scale = ""
    if "sigma_model_rtest" in s.index:
        r = s.loc["sigma_model_rtest"]
        scale = (f" The R-test's own discrepancy scale σ_model (what its model leaves out; prior "
                 f"{_prior_text(rep, 'sigma_model_rtest')}): posterior mean {r['mean']:.2f} µm, 95 % HDI "
                 f"{r['hdi_low']:.2f} to {r['hdi_high']:.2f} µm.")
    page.paragraph(
        f"Each position of a run gives three readings (the sphere centre's displacement from the nest centre along "
        f"the sensors' axes, docs/rtest.md). {n_out} of {len(readings)} observed means fall outside their 95 % "
        f"predictive interval; largest |z| {float(np.abs(readings['z']).max()):.2f}, rms residual "
        f"{float(np.sqrt(np.mean(readings['residual_um'] ** 2))):.2f} µm." + scale + " rtest.csv.")
    page.figure(tmp / "rtest.png", CAPTION, "R-test readings and their posterior predictive")
    page.table(readings.set_index(["run", "position"])[["angles_deg", "component", "observed_mean_um",
                                                        "predictive_mean_um", "predictive_sd_um", "residual_um",
                                                        "z", "inside_95"]],
               digits={"observed_mean_um": 2, "predictive_mean_um": 2, "predictive_sd_um": 2, "residual_um": 2,
                       "z": 2})
    page.paragraph("The R-test's nuisance terms (docs/rtest.md, 'The nuisance terms'): each run zeroed at its first "
                   "position has its sensors' zero (a broad prior: only the changes along the run inform), each "
                   "sphere placement its error on the workpiece side at the home pose, each uncalibrated nest its "
                   "length error and its centre's offset across the spindle; all in µm." +
                   (" 'truth': the campaign's stated truth." if "truth" in terms else "") + " rtest_terms.csv.")
    page.table(terms.set_index("term"), digits=2)


def _prior_text(rep, name: str) -> str:
    prior = next(p for p in rep.log_posterior.priors.priors if p.name == name)
    return prior.describe()
