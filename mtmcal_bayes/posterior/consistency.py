"""Do the ball bar and the touch probe agree?  Each instrument's readings predicted from the other's posterior.

For each direction (probe readings given the ball-bar-only posterior, ball-bar eccentricities given the
probe-only posterior) the posterior predictive of the other instrument's observations is

    y ~ f(θ) + A_η η + noise,   θ from the source posterior's draws, η the target's own nuisance terms

with ``η`` (stylus, sphere and datum terms for the probe; T-ball and W-ball terms for the ball bar)
unknown to the source posterior and so drawn from its prior.  The model is linear in ``η`` (exactly
for the probe's datum and placement terms, to first order for the rest), so their part of the
predictive covariance is ``A_η Σ_η A_ηᵀ`` in closed form; the draws give the rest; the noise is the
likelihood's with the target instrument's own discrepancy scale at its prior mean of σ² (the source
posterior, which has not seen the target's data, knows nothing of it).  Broad datum terms (prior sd ≥ 1 mm: where
the sphere sits in the reading frame) are profiled out as flat: the residual is the generalised
least-squares residual orthogonal to their columns, with as many fewer degrees of freedom.

Per reading group (the probe's C-axis run, its B-axis run of each stylus, each ball-bar run) the
check gives ``χ² = rᵀ S⁻¹ r`` on the group's ``dof``, its p-value, the standardised residuals
``z`` of the readings, and a verdict: *agree* (p ≥ 0.01) or *disagree*.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

from .. import units
from ..analysis import CampaignAnalysis
from ..inference.approximation import PosteriorApproximation
from ..inference.log_posterior import LogPosterior
from ..models import jacobian
from ..observations import ProbeKey

#: a group whose p-value is below this disagrees
P_DISAGREE = 0.01
#: nuisance terms at least this broad (mm) are profiled out as flat
BROAD = 1.0
#: posterior draws used per direction
N_DRAWS = 4000


@dataclass
class Consistency:
    """The two directions of the check: per reading (``readings``) and per group (``groups``)."""

    readings: pd.DataFrame
    groups: pd.DataFrame

    def to_text(self) -> str:
        lines = ["Consistency of the instruments (posterior predictive of one from the other's posterior):"]
        for _, g in self.groups.iterrows():
            lines.append(f"  {g['verdict']:9s} {g['group']} given the {g['given']}-only posterior: "
                         f"χ² = {g['chi2']:.1f} on {g['dof']} dof, p = {g['p_value']:.2g}, "
                         f"largest |z| = {g['max_abs_z']:.1f} ({g['worst']})")
        return "\n".join(lines)

    def to_json(self) -> dict:
        return {"groups": self.groups.to_dict(orient="records"), "readings": self.readings.to_dict(orient="records")}

    @property
    def disagreeing(self) -> list[str]:
        return list(self.groups.loc[self.groups["verdict"] == "disagree", "group"])


def reading_group(key) -> str:
    """The reading group of an observation key: a probe run (of one stylus) or a ball-bar run."""
    return key.group if isinstance(key, ProbeKey) else f"ball bar {key.pattern}@{key.setup}/{key.mount}"


def _log_posterior(source) -> LogPosterior:
    """The log posterior behind a :class:`~.sample.PosteriorResult`, a :class:`CampaignAnalysis` or itself."""
    if isinstance(source, CampaignAnalysis):
        return source.log_posterior
    return source if isinstance(source, LogPosterior) else source.log_posterior


def source_draws(source, n_draws: int = N_DRAWS, seed: int = 0) -> np.ndarray:
    """``n_draws`` posterior draws ``(n, q)`` (internal units) of ``source``: a :class:`~.sample.PosteriorResult`'s
    kept chain, or exact draws of a :class:`LogPosterior` of the linear model (its σ-marginal posterior), or of a
    :class:`CampaignAnalysis` of the linear model (from the exact posterior it has built)."""
    rng = np.random.default_rng(seed)
    if isinstance(source, (LogPosterior, CampaignAnalysis)):
        approx = source.approximation if isinstance(source, CampaignAnalysis) else PosteriorApproximation(source)
        source = _log_posterior(source)
        theta, sigma = approx.marginal.draw(source.likelihood.y, n_draws, rng)
        return np.column_stack([theta, sigma]) if source.fixed_sigma is None else theta
    flat = source.sampling.chains.reshape(-1, source.sampling.chains.shape[-1])
    return flat[rng.choice(len(flat), size=min(n_draws, len(flat)), replace=False)]


def target_noise(target: LogPosterior) -> np.ndarray:
    """Noise variance ``(m,)`` of the target's observations, mm²: its base noise plus its own discrepancy scale at
    the prior mean of σ² (or as fixed)."""
    if target.fixed_sigma is not None:
        return target.likelihood.variance_at(target.fixed_sigma)
    second = np.array([q.sd**2 + q.mean**2 for q in target.priors.priors[target.p:]])
    return target.likelihood.base_var + second[target.scale_of]


def predictive_check(source, target: LogPosterior, n_draws: int = N_DRAWS, seed: int = 0, *,
                     draws: np.ndarray | None = None):
    """Standardised residuals and group verdicts of ``target``'s observations under ``source``'s posterior.

    ``source`` is a :class:`~.sample.PosteriorResult`, or the :class:`LogPosterior` or :class:`CampaignAnalysis` of a
    linear model (its exact posterior is drawn); ``target`` the log posterior of the other data; ``draws`` (n, q) the
    source's posterior draws when they are at hand (then ``n_draws`` and ``seed`` are not used).
    Returns ``(readings DataFrame, groups DataFrame)``.
    """
    post_s = _log_posterior(source)
    draws = source_draws(source, n_draws, seed) if draws is None else draws
    shared = [n for n in target.space.names if n in post_s.space.names]
    own = [i for i, n in enumerate(target.space.names) if n not in post_s.space.names]
    theta = np.zeros((len(draws), target.p))
    for n in shared:
        theta[:, target.space.index(n)] = draws[:, post_s.space.names.index(n)]
    model = target.forward
    pred = model.predict(theta)  # own nuisance terms at zero
    A = model.design if hasattr(model, "design") else jacobian(model)
    prior_sd = target.priors.width[: target.p]
    broad = [i for i in own if prior_sd[i] >= BROAD]
    narrow = [i for i in own if prior_sd[i] < BROAD]
    S = np.cov(pred, rowvar=False) + (A[:, narrow] * prior_sd[narrow] ** 2) @ A[:, narrow].T
    S += np.diag(target_noise(target))
    r_all = target.likelihood.y - pred.mean(axis=0)
    keys = model.observations.keys
    groups = {}
    for j, k in enumerate(keys):
        groups.setdefault(reading_group(k), []).append(j)
    rows, verdicts = [], []
    given = "ball-bar" if post_s.data == "ballbar" else ("probe" if post_s.data == "probe" else "fused")
    for name, idx in groups.items():
        idx = np.array(idx)
        Sg, r = S[np.ix_(idx, idx)], r_all[idx]
        B = A[np.ix_(idx, broad)]
        B = B[:, np.abs(B).max(axis=0) > 0] if B.size else B
        Si = np.linalg.inv(Sg)
        if B.size:  # generalised least squares: profile the flat datum terms out
            M = np.linalg.inv(B.T @ Si @ B)
            res = r - B @ (M @ (B.T @ Si @ r))
            cov = Sg - B @ M @ B.T
            rank = np.linalg.matrix_rank(B)
        else:
            res, cov, rank = r, Sg, 0
        chi2 = float(res @ Si @ res)
        dof = len(idx) - rank
        with np.errstate(invalid="ignore", divide="ignore"):
            z = np.where(np.diag(cov) > 1e-12 * np.max(np.diag(Sg)), res / np.sqrt(np.abs(np.diag(cov))), 0.0)
        p = float(stats.chi2.sf(chi2, dof)) if dof > 0 else float("nan")
        worst = int(np.argmax(np.abs(z)))
        labels = [keys[j].label for j in idx]
        for j, lab, zi, ri in zip(idx, labels, z, res):
            rows.append({"given": given, "group": name, "reading": lab,
                         "observed_um": units.from_internal(target.likelihood.y[j], "um"),
                         "predictive_mean_um": units.from_internal(pred[:, j].mean(), "um"),
                         "predictive_sd_um": units.from_internal(np.sqrt(S[j, j]), "um"),
                         "residual_um": units.from_internal(ri, "um"), "z": float(zi)})
        verdicts.append({"given": given, "group": name, "chi2": chi2, "dof": int(dof), "p_value": p,
                         "max_abs_z": float(np.abs(z).max()), "worst": labels[worst],
                         "verdict": "agree" if not p < P_DISAGREE else "disagree"})
    return pd.DataFrame(rows), pd.DataFrame(verdicts)


def instrument_consistency(ballbar, probe, n_draws: int = N_DRAWS, seed: int = 0) -> Consistency:
    """Both directions: probe readings given the ball-bar-only posterior ``ballbar``, ball-bar eccentricities
    given the probe-only posterior ``probe`` (both :class:`~.sample.PosteriorResult` of one campaign and model, or
    both :class:`LogPosterior` or :class:`CampaignAnalysis` of the linear model, whose exact posteriors are drawn)."""
    post_b, post_p = _log_posterior(ballbar), _log_posterior(probe)
    a = predictive_check(ballbar, post_p, n_draws, seed)
    b = predictive_check(probe, post_b, n_draws, seed)
    return Consistency(pd.concat([a[0], b[0]], ignore_index=True), pd.concat([a[1], b[1]], ignore_index=True))


#: labels of the three posteriors, by the data they use
DATA_LABELS = {"ballbar": "ball bar only", "probe": "probe only", "both": "fused"}


@dataclass
class InstrumentComparison:
    """Ball-bar-only, probe-only and fused posteriors of one campaign and model, and their consistency.

    ``intervals``: one row per quantity and data set (mean, sd, 95 % HDI); ``disagreements``: sentences
    naming each quantity whose ball-bar-only and probe-only 95 % HDIs do not overlap.
    """

    posteriors: dict
    consistency: Consistency
    intervals: pd.DataFrame
    disagreements: list[str]

    def to_text(self) -> str:
        lines = [self.consistency.to_text(), "", "Posterior sd by data (ball bar only / probe only / fused):"]
        sd = self.intervals.pivot(index="quantity", columns="data", values="sd")
        for q in sd.index:
            lines.append(f"  {q:18s} " + " / ".join(f"{sd.loc[q, DATA_LABELS[d]]:.3g}" for d in DATA_LABELS))
        return "\n".join(lines + [""] + (self.disagreements or ["No quantity's ball-bar-only and probe-only 95 % "
                                                                 "HDIs are disjoint."]))


def compare_instruments(posteriors: dict, sample) -> InstrumentComparison:
    """The three posteriors (``posteriors`` holds those already sampled, by data; ``sample(data)`` samples
    the others) and the consistency of the two instruments."""
    posteriors = dict(posteriors)
    for data in DATA_LABELS:
        if data not in posteriors:
            posteriors[data] = sample(data)
    posteriors = {d: posteriors[d] for d in DATA_LABELS}
    cons = instrument_consistency(posteriors["ballbar"], posteriors["probe"])
    rows = []
    for data, res in posteriors.items():
        for q, r in res.summary.iterrows():
            rows.append({"quantity": q, "data": DATA_LABELS[data], "mean": r["mean"], "sd": r["sd"],
                         "hdi_low": r["hdi_low"], "hdi_high": r["hdi_high"], "unit": r["unit"]})
    intervals = pd.DataFrame(rows)
    b, p = posteriors["ballbar"].summary, posteriors["probe"].summary
    out = []
    for q in b.index:
        if q in p.index and (b.loc[q, "hdi_high"] < p.loc[q, "hdi_low"] or p.loc[q, "hdi_high"] < b.loc[q, "hdi_low"]):
            u = units.SYMBOL[b.loc[q, "unit"]]
            out.append(f"{q}: the instruments disagree — ball bar {b.loc[q, 'mean']:.1f} {u} "
                       f"[{b.loc[q, 'hdi_low']:.1f}, {b.loc[q, 'hdi_high']:.1f}], probe {p.loc[q, 'mean']:.1f} {u} "
                       f"[{p.loc[q, 'hdi_low']:.1f}, {p.loc[q, 'hdi_high']:.1f}]: disjoint 95 % HDIs")
    return InstrumentComparison(posteriors, cons, intervals, out)
