"""Do the instruments agree?  Each instrument's readings predicted from the other's posterior, pair by pair.

For each pair of the campaign's instruments (the ball bar, the touch probe, the R-test) and each direction (probe
readings given the ball-bar-only posterior, ball-bar eccentricities given the probe-only posterior, and so on) the
posterior predictive of the other instrument's observations is

    y ~ f(θ) + A_η η + noise,   θ from the source posterior's draws, η the target's own nuisance terms

with ``η`` (stylus, sphere and datum terms for the probe; T-ball and W-ball terms for the ball bar; a run's zero,
a sphere's placement and a nest's length and centring for the R-test) unknown to the source posterior and so drawn from its prior.  The model is linear in ``η`` (exactly
for the probe's datum and placement terms, to first order for the rest), so their part of the
predictive covariance is ``A_η Σ_η A_ηᵀ`` in closed form; the draws give the rest; the noise is the
likelihood's with the target instrument's own discrepancy scale at its prior mean of σ² (the source
posterior, which has not seen the target's data, knows nothing of it).

The target's own nuisance terms whose prior is broad against the readings' noise (:data:`FLAT`: at one prior sd
they move a reading of the group by more than 30 noise sd: the sphere's placement, the stylus length, the reading
datum) are profiled out as flat: the residual is the generalised least-squares residual orthogonal to their
columns ``B``, and the χ² is taken on the directions they leave free.  Its degrees of freedom are the rank of the
predictive covariance after them, ``m − rank(B)`` for a group of ``m`` readings (``S`` has full rank: it holds
the noise), not ``m``: in a direction a broad term spans, the predictive variance is the term's prior, a reading
there says nothing, and counting it as a degree of freedom makes the check insensitive (χ² ≪ dof).  The narrower
nuisance terms (the T ball's centring, the W ball's clamping, the stylus centring) stay in ``S`` with their priors.

Per reading group (a probe run of one stylus, each ball-bar run, each R-test run) the check gives ``χ² = rᵀ S⁻¹ r`` of that
residual on the group's ``dof``, its p-value, the standardised residuals ``z`` of the readings (each residual over
its sd after the profiling), and a verdict: *agree* (p ≥ 0.01), *disagree*, or *unchecked* (no free direction).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from scipy import stats

from .. import units
from ..analysis import CampaignAnalysis
from ..inference.approximation import PosteriorApproximation
from ..inference.log_posterior import LogPosterior
from ..models import jacobian
from ..observations import ProbeKey, RTestKey

#: a group whose p-value is below this disagrees
P_DISAGREE = 0.01
#: a target's own nuisance term that moves a reading of a group by more than this many noise sd at one prior sd is
#: profiled out of the group's check as flat (its prior then carries < 1/900 of a reading's information there)
FLAT = 30.0
#: the verdict of a group whose readings the flat terms leave no free direction (no χ² to take)
UNCHECKED = "unchecked"
#: equal-probability nodes of the target's discrepancy-scale prior a group's p-value is averaged over
SIGMA_NODES = 256
#: posterior draws used per direction
N_DRAWS = 4000
#: what a posterior of one instrument's data is called in "… given the <label>-only posterior", by its data
GIVEN_LABEL = {"ballbar": "ball-bar", "probe": "probe", "rtest": "R-test"}


@dataclass
class Consistency:
    """The two directions of the check: per reading (``readings``) and per group (``groups``); a check of several
    pairs of instruments (:func:`pairwise`) names each row's pair in a first column ``pair``."""

    readings: pd.DataFrame
    groups: pd.DataFrame

    def to_text(self) -> str:
        if "pair" not in self.groups:
            return "\n".join(["Consistency of the instruments (posterior predictive of one from the other's "
                              "posterior):"] + [_group_line(g, "  ") for _, g in self.groups.iterrows()])
        lines = ["Consistency of the instruments, pair by pair (posterior predictive of one from the other's "
                 "posterior):"]
        for pair, groups in self.groups.groupby("pair", sort=False):
            lines.append(f"  {pair}:")
            lines += [_group_line(g, "    ") for _, g in groups.iterrows()]
        return "\n".join(lines)

    def to_json(self) -> dict:
        return {"groups": self.groups.to_dict(orient="records"), "readings": self.readings.to_dict(orient="records")}

    @property
    def disagreeing(self) -> list[str]:
        """The groups that disagree (each once, though several of the other instruments' posteriors see it)."""
        return list(dict.fromkeys(self.groups.loc[self.groups["verdict"] == "disagree", "group"]))


def _group_line(g, indent: str) -> str:
    """One line of the text: a group's verdict given the other instrument's posterior."""
    if g["verdict"] == UNCHECKED:
        return (f"{indent}{g['verdict']:9s} {g['group']} given the {g['given']}-only posterior: its nuisance terms "
                "leave its readings no free direction")
    return (f"{indent}{g['verdict']:9s} {g['group']} given the {g['given']}-only posterior: "
            f"χ² = {g['chi2']:.1f} on {g['dof']} dof, p = {g['p_value']:.2g}, "
            f"largest |z| = {g['max_abs_z']:.1f} ({g['worst']})")


def pairwise(checks: dict[str, Consistency]) -> Consistency:
    """One :class:`Consistency` of several pairs' checks ``{pair label: its check}``, each row naming its pair (a
    single pair's check is returned as it is)."""
    if len(checks) == 1:
        return next(iter(checks.values()))
    named = [(c.readings.assign(pair=pair), c.groups.assign(pair=pair)) for pair, c in checks.items()]

    def first(df):
        return df[["pair"] + [c for c in df.columns if c != "pair"]]

    return Consistency(first(pd.concat([r for r, _ in named], ignore_index=True)),
                       first(pd.concat([g for _, g in named], ignore_index=True)))


def reading_group(key) -> str:
    """The reading group of an observation key: a probe run (of one stylus), an R-test run or a ball-bar run."""
    return key.group if isinstance(key, (ProbeKey, RTestKey)) else f"ball bar {key.pattern}@{key.setup}/{key.mount}"


def reading_groups(keys) -> dict[str, np.ndarray]:
    """``{group: row indices}`` of observation ``keys``, in the order the groups first appear."""
    groups: dict[str, list[int]] = {}
    for j, k in enumerate(keys):
        groups.setdefault(reading_group(k), []).append(j)
    return {g: np.array(idx) for g, idx in groups.items()}


def flat_terms(A_rows: np.ndarray, prior_sd: np.ndarray, own, noise_var: np.ndarray) -> list[int]:
    """The columns among ``own`` (the target's own nuisance terms) profiled out of a group's check: those that
    move one of the group's readings by more than :data:`FLAT` noise sd at one prior sd.

    ``A_rows`` (m, p) the design's rows of the group, mm per internal unit; ``prior_sd`` (p,) the prior sds;
    ``noise_var`` (m,) the readings' noise variance, mm²."""
    effect = np.abs(A_rows) * prior_sd[None, :] / np.sqrt(noise_var)[:, None]
    return [i for i in own if effect[:, i].max() > FLAT]


def column_basis(B: np.ndarray) -> np.ndarray:
    """An orthonormal basis ``(m, rank)`` of the column space of ``B`` (m, k) (singular values above 1e-9 of the
    largest)."""
    if not B.size:
        return np.zeros((B.shape[0], 0))
    U, sv, _ = np.linalg.svd(B, full_matrices=False)
    return U[:, sv > 1e-9 * sv[0]] if sv[0] > 0 else np.zeros((B.shape[0], 0))


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
    noise = target_noise(target)
    Sd = np.cov(pred, rowvar=False) + np.diag(noise)
    r_all = target.likelihood.y - pred.mean(axis=0)
    keys = model.observations.keys
    rows, verdicts = [], []
    given = GIVEN_LABEL.get(post_s.data, "fused")
    for name, idx in reading_groups(keys).items():
        flat = flat_terms(A[idx], prior_sd, own, noise[idx])
        narrow = [i for i in own if i not in flat]
        An = A[np.ix_(idx, narrow)]
        Sg = Sd[np.ix_(idx, idx)] + (An * prior_sd[narrow] ** 2) @ An.T
        r = r_all[idx]
        B = column_basis(A[np.ix_(idx, flat)])  # flat terms can be collinear (a stylus length and a datum along it)
        Si = np.linalg.inv(Sg)
        if B.shape[1]:  # generalised least squares: profile the flat terms out (S's part along B would not matter)
            M = np.linalg.inv(B.T @ Si @ B)
            res = r - B @ (M @ (B.T @ Si @ r))
            cov = Sg - B @ M @ B.T
        else:
            res, cov = r, Sg
        rank = B.shape[1]
        chi2 = float(res @ Si @ res)
        dof = len(idx) - rank
        p = _p_value(chi2, Sg, B, target=target, idx=idx) if dof > 0 else float("nan")
        with np.errstate(invalid="ignore", divide="ignore"):
            z = np.where(np.diag(cov) > 1e-12 * np.max(np.diag(Sg)), res / np.sqrt(np.abs(np.diag(cov))), 0.0)
        worst = int(np.argmax(np.abs(z)))
        labels = [keys[j].label for j in idx]
        for j, lab, zi, ri, vi in zip(idx, labels, z, res, np.diag(Sg)):
            rows.append({"given": given, "group": name, "reading": lab,
                         "observed_um": units.from_internal(target.likelihood.y[j], "um"),
                         "predictive_mean_um": units.from_internal(pred[:, j].mean(), "um"),
                         "predictive_sd_um": units.from_internal(np.sqrt(vi), "um"),
                         "residual_um": units.from_internal(ri, "um"), "z": float(zi)})
        verdicts.append({"given": given, "group": name, "chi2": chi2, "dof": int(dof), "p_value": p,
                         "max_abs_z": float(np.abs(z).max()), "worst": labels[worst],
                         "verdict": UNCHECKED if dof == 0 else ("disagree" if p < P_DISAGREE else "agree")})
    return pd.DataFrame(rows), pd.DataFrame(verdicts)


def _p_value(chi2: float, Sg: np.ndarray, B: np.ndarray, *, target: LogPosterior, idx: np.ndarray) -> float:
    """The p-value of a group's ``chi2`` under the target's prior predictive, its discrepancy scale σ unknown.

    ``chi2`` was taken with σ² at its prior mean σ₀² (in ``Sg``, the group's predictive covariance; ``B`` the
    orthonormal basis of the flat columns).  On the free directions ``Q`` (orthonormal, ``Qᵀ B = 0``) the
    covariance is ``C + σ² I`` with ``C = Qᵀ (Sg − σ₀² I) Q``, so given σ the statistic is ``Σ_k c_k χ²₁`` with
    ``c_k = (λ_k + σ²) / (λ_k + σ₀²)`` (``λ`` the eigenvalues of ``C``): the χ² on ``dof`` when σ = σ₀.  Its tail
    is averaged over :data:`SIGMA_NODES` equal-probability nodes of σ's prior, each by Satterthwaite's scaled
    χ² (exact when the ``c_k`` are equal: where the noise dominates).  With σ fixed, the plain χ² tail."""
    dof = len(idx) - B.shape[1]
    if target.fixed_sigma is not None:
        return float(stats.chi2.sf(chi2, dof))
    scale = np.unique(target.scale_of[idx])
    if len(scale) != 1:
        raise ValueError("a reading group of two discrepancy scales")  # a group is one instrument's
    prior = target.priors.priors[target.p + int(scale[0])]
    s0sq = prior.sd**2 + prior.mean**2
    Q = np.linalg.svd(B, full_matrices=True)[0][:, B.shape[1]:] if B.shape[1] else np.eye(len(idx))
    lam = np.clip(np.linalg.eigvalsh(Q.T @ (Sg - s0sq * np.eye(len(idx))) @ Q), 0.0, None)
    sigma_sq = prior.frozen().ppf((np.arange(SIGMA_NODES) + 0.5) / SIGMA_NODES) ** 2
    c = (lam[None, :] + sigma_sq[:, None]) / (lam[None, :] + s0sq)  # (nodes, dof)
    scale_c, nu = (c**2).sum(axis=1) / c.sum(axis=1), c.sum(axis=1) ** 2 / (c**2).sum(axis=1)
    return float(np.mean(stats.chi2.sf(chi2 / scale_c, nu)))


def instrument_consistency(ballbar, probe, n_draws: int = N_DRAWS, seed: int = 0) -> Consistency:
    """Both directions: probe readings given the ball-bar-only posterior ``ballbar``, ball-bar eccentricities
    given the probe-only posterior ``probe`` (both :class:`~.sample.PosteriorResult` of one campaign and model, or
    both :class:`LogPosterior` or :class:`CampaignAnalysis` of the linear model, whose exact posteriors are drawn).
    Any two instruments' posteriors alike (the first's readings given the second's, then the other way)."""
    post_b, post_p = _log_posterior(ballbar), _log_posterior(probe)
    a = predictive_check(ballbar, post_p, n_draws, seed)
    b = predictive_check(probe, post_b, n_draws, seed)
    return Consistency(pd.concat([a[0], b[0]], ignore_index=True), pd.concat([a[1], b[1]], ignore_index=True))


#: labels of the three posteriors of the ball bar and the probe, by the data they use
DATA_LABELS = {"ballbar": "ball bar only", "probe": "probe only", "both": "fused"}
#: each instrument's own posterior in words, by its data name
ALONE_LABELS = {"ballbar": "ball bar only", "probe": "probe only", "rtest": "R-test only"}


def comparison_labels(instruments=("ballbar", "probe")) -> dict[str, str]:
    """``{data: label}`` of an instruments' comparison: each instrument alone, then all of them fused (``"both"``
    for the ball bar and the probe, :data:`DATA_LABELS`; ``"all"`` with the R-test besides)."""
    instruments = tuple(instruments)
    fused = "both" if instruments == ("ballbar", "probe") else "all"
    return {**{i: ALONE_LABELS[i] for i in instruments}, fused: "fused"}
#: every data value in words (the R-test's too: :data:`~mtmcal_bayes.parameters.DATA_INSTRUMENTS`)
DATA_WORDS = {**DATA_LABELS, "rtest": "R-test only", "ballbar+rtest": "ball bar and R-test",
              "probe+rtest": "probe and R-test", "all": "every instrument"}


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
    labels: dict = field(default_factory=lambda: dict(DATA_LABELS))  # {data: label}, each alone, then fused

    @property
    def fused(self):
        """The posterior of every compared instrument's data."""
        return self.posteriors[list(self.labels)[-1]]

    def to_text(self) -> str:
        lines = [self.consistency.to_text(), "", f"Posterior sd by data ({' / '.join(self.labels.values())}):"]
        sd = self.intervals.pivot(index="quantity", columns="data", values="sd")
        for q in sd.index:
            lines.append(f"  {q:18s} " + " / ".join(f"{sd.loc[q, label]:.3g}" for label in self.labels.values()))
        return "\n".join(lines + [""] + (self.disagreements or ["No quantity's ball-bar-only and probe-only 95 % "
                                                                 "HDIs are disjoint."]))


def compare_instruments(posteriors: dict, sample, instruments=("ballbar", "probe")) -> InstrumentComparison:
    """The posteriors of each of ``instruments`` alone and of all of them fused (:func:`comparison_labels`;
    ``posteriors`` holds those already sampled, by data; ``sample(data)`` samples the others) and the consistency of
    the ball bar and the probe (every pair with the R-test: :func:`~.instrument_check.check_instruments`)."""
    labels = comparison_labels(instruments)
    posteriors = dict(posteriors)
    for data in labels:
        if data not in posteriors:
            posteriors[data] = sample(data)
    posteriors = {d: posteriors[d] for d in labels}
    cons = instrument_consistency(posteriors["ballbar"], posteriors["probe"])
    rows = []
    for data, res in posteriors.items():
        for q, r in res.summary.iterrows():
            rows.append({"quantity": q, "data": labels[data], "mean": r["mean"], "sd": r["sd"],
                         "hdi_low": r["hdi_low"], "hdi_high": r["hdi_high"], "unit": r["unit"]})
    intervals = pd.DataFrame(rows)
    out = []
    alone = [d for d in labels if d in ALONE_LABELS]
    for i, first in enumerate(alone):
        for second in alone[i + 1:]:
            b, p = posteriors[first].summary, posteriors[second].summary
            for q in b.index:
                if q in p.index and (b.loc[q, "hdi_high"] < p.loc[q, "hdi_low"]
                                     or p.loc[q, "hdi_high"] < b.loc[q, "hdi_low"]):
                    u = units.SYMBOL[b.loc[q, "unit"]]
                    out.append(f"{q}: the instruments disagree — {_ALONE_WORD[first]} {b.loc[q, 'mean']:.1f} {u} "
                               f"[{b.loc[q, 'hdi_low']:.1f}, {b.loc[q, 'hdi_high']:.1f}], {_ALONE_WORD[second]} "
                               f"{p.loc[q, 'mean']:.1f} {u} [{p.loc[q, 'hdi_low']:.1f}, {p.loc[q, 'hdi_high']:.1f}]: "
                               "disjoint 95 % HDIs")
    return InstrumentComparison(posteriors, cons, intervals, out, labels)


#: each instrument in the disagreements' sentences
_ALONE_WORD = {"ballbar": "ball bar", "probe": "probe", "rtest": "R-test"}
