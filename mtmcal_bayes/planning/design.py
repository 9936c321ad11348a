"""Closed-form expected posterior of candidate measurements (SPEC §6).

With normal priors, the linear model and the Gaussian likelihood at a fixed
``sigma_model``, the posterior precision after adding a run is the current
precision plus ``Aᶜᵀ W Aᶜ`` (``Aᶜ`` the run's rows of the design matrix, ``W``
the inverse variances of its repeat means), whatever the data turn out to be.
So the expected posterior sd of every target and the expected information
gain about the targets, ``½·log₂(det Σ_T,before / det Σ_T,after)`` bits (the
mutual information between the new data and the targets), are exact for the
linear model and take one batched matrix inverse for all candidates.  The
kinematic models are linearised at zero (their nonlinearity is below 0.1 µm
at the thesis deviations, bench/nonlinearity.py).

More repeats of an existing run do not add rows: they shrink ``s²/n`` in the
variance ``s²/n + u_inst² + sigma_model²`` of that run's means, and only
that term (the instrument error and the model discrepancy do not average out).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from .. import units
from ..campaign import Run
from ..errors import ParameterError
from ..inference.analytic import NOT_IDENTIFIED_GROWTH, WIDEN
from ..inference.likelihood import GaussianMeanLikelihood
from ..inference.log_posterior import SAMPLED_DEVIATIONS
from ..inference.priors import make_prior
from ..models.linear import LinearModel
from ..observations import Observations
from ..parameters import IDENTIFIABLE, QUANTITIES, ParameterSpace, weights
from ..patterns import COMPONENTS
from .candidates import Candidate

#: a candidate that changes no target's sd by this fraction identifies nothing new
MIN_GAIN = 0.01


def check_targets(targets) -> list[str]:
    allowed = list(IDENTIFIABLE) + [d for d in SAMPLED_DEVIATIONS if d not in IDENTIFIABLE]
    targets = list(targets or IDENTIFIABLE)
    for t in targets:
        if t not in allowed:
            raise ParameterError("targets", f"unknown quantity {t!r} (expected one of: {', '.join(allowed)})")
    return list(dict.fromkeys(targets))


def default_sigma_model(campaign) -> float:
    """Root mean square of the sigma_model prior, mm: the fixed value the closed form uses."""
    prior = make_prior("sigma_model", "sigma_model", "length", campaign.priors).frozen()
    return float(np.sqrt(prior.var() + prior.mean() ** 2))


@dataclass
class Evaluation:
    """Expected results of K candidates for t targets (display units: ″, µm).

    ``sd_before`` (t,), ``sd_after`` (K, t), ``eig_bits`` (K,), ``identified_before`` (t,),
    ``identified_after`` (K, t) by the prior-sensitivity rule of the inference.
    """

    targets: list[str]
    units: list[str]
    sd_before: np.ndarray
    sd_after: np.ndarray
    eig_bits: np.ndarray
    identified_before: np.ndarray
    identified_after: np.ndarray

    @property
    def informative(self) -> np.ndarray:
        """(K,) whether some target's sd falls by at least :data:`MIN_GAIN`."""
        return np.any(self.sd_after < (1.0 - MIN_GAIN) * self.sd_before, axis=1)


class Planner:
    """The current closed-form posterior of a campaign and the rows of candidate runs.

    Parameters
    ----------
    campaign : Campaign
    candidates : list of Candidate (their new setups/mounts join the parameter space)
    targets : quantity names (default the eight identifiable ones)
    sigma_model : fixed model-discrepancy sd, mm (default :func:`default_sigma_model`)
    """

    def __init__(self, campaign, candidates: list[Candidate], targets=None, *, sigma_model: float | None = None,
                 model: str = "linear"):
        self.campaign = campaign
        self.model = model
        self.candidates = list(candidates)
        self.targets = check_targets(targets)
        self.sigma_model = default_sigma_model(campaign) if sigma_model is None else float(sigma_model)
        bb = campaign.ballbar
        setups = dict(bb.setups)
        mounts = dict(bb.mounts)
        for c in self.candidates:
            setups.setdefault(c.setup.id, c.setup)
            mounts.setdefault(c.mount.id, c.mount)
        self._setups, self._mounts = setups, mounts
        self.space = ParameterSpace(list(setups), list(mounts), SAMPLED_DEVIATIONS)
        priors = [make_prior(p.name, p.base, p.kind, campaign.priors) for p in self.space.parameters]
        self.prior_var = np.array([p.sd for p in priors]) ** 2
        self.is_deviation = np.array([p.group == "deviation" for p in self.space.parameters])
        obs = Observations.from_campaign(campaign)
        lik = GaussianMeanLikelihood(obs, bb.accuracy)
        self.observations = obs
        self.pooled_sd = obs.pooled_sd()
        self.A = self._design(campaign) if len(obs) else np.zeros((0, len(self.space)))
        self.V = lik.base_var + self.sigma_model**2
        self.T = np.zeros((len(self.targets), len(self.space)))
        for i, t in enumerate(self.targets):
            for name, w in weights(t).items():
                self.T[i, self.space.index(name)] = w
        self.target_units = [QUANTITIES[t].unit for t in self.targets]

    # ------------------------------------------------------------------ rows
    def _design(self, campaign) -> np.ndarray:
        """Design matrix ``(m, P)`` of ``campaign``'s runs: the linear model, or a kinematic model linearised at zero."""
        if self.model == "linear":
            return LinearModel(campaign, self.space).design
        from ..models.kinematic import HTMModel, jacobian

        return jacobian(HTMModel(campaign, self.model, self.space))

    def noise_var(self, repeats: int) -> float:
        """Variance of one repeat mean of a new run, mm²."""
        return self.pooled_sd**2 / repeats + self.campaign.ballbar.accuracy**2 + self.sigma_model**2

    def candidate_rows(self, candidates: list[Candidate] | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
        """For each candidate, its rows ``(k, P)`` and precision weights ``(k,)`` (1/mm²)."""
        candidates = self.candidates if candidates is None else candidates
        out: list = [None] * len(candidates)
        by_length: dict[float, list[int]] = {}
        for i, c in enumerate(candidates):
            if c.repeat_of is None:
                by_length.setdefault(c.length, []).append(i)
            else:
                out[i] = self._repeat_rows(c)
        for length, idx in by_length.items():
            rows = self._new_run_rows([candidates[i] for i in idx], length)
            for i, r in zip(idx, rows):
                out[i] = r
        return out

    def _repeat_rows(self, c: Candidate):
        keys = [j for j, k in enumerate(self.observations.keys) if k.run == c.repeat_of]
        n = self.observations.n[keys]
        s2 = np.where(n > 1, np.nan_to_num(self.observations.sd[keys]) ** 2, self.pooled_sd**2)
        v_new = self.V[keys] - s2 / n + s2 / (n + c.repeats)
        return self.A[keys], 1.0 / v_new - 1.0 / self.V[keys]

    def _new_run_rows(self, candidates: list[Candidate], length: float):
        """Rows of new runs from one linear model over the campaign plus the runs (bar length ``length``)."""
        aug = copy.copy(self.campaign)
        bb = copy.copy(self.campaign.ballbar)
        bb.length = length
        bb.setups, bb.mounts = self._setups, self._mounts
        m0 = len(bb.runs)
        bb.runs = list(bb.runs) + [Run(c.pattern, c.setup.id, c.mount.id,
                                       {comp: np.zeros(c.repeats) for comp in COMPONENTS[c.pattern]})
                                   for c in candidates]
        aug.ballbar = bb
        design = self._design(aug)
        keys = Observations.from_campaign(aug).keys
        out = []
        for j, c in enumerate(candidates):
            rows = [i for i, k in enumerate(keys) if k.run == m0 + j]
            out.append((design[rows], np.full(len(rows), 1.0 / self.noise_var(c.repeats))))
        return out

    # ------------------------------------------------------------------ posterior
    def _precision(self, widen: float = 1.0) -> np.ndarray:
        var0 = self.prior_var * np.where(self.is_deviation, widen**2, 1.0)
        return np.diag(1.0 / var0) + self.A.T @ (self.A / self.V[:, None])

    def _target_cov(self, precisions: np.ndarray) -> np.ndarray:
        cov = np.linalg.inv(precisions)
        return self.T @ cov @ self.T.T

    def evaluate(self, candidates: list[Candidate] | None = None) -> Evaluation:
        """Expected target sds, information gain and identifiability after each candidate."""
        candidates = self.candidates if candidates is None else candidates
        rows = self.candidate_rows(candidates)
        added = np.stack([A.T @ (A * w[:, None]) for A, w in rows]) if rows else np.zeros((0,) + (len(self.space),) * 2)
        to_display = np.array([units.from_internal(1.0, u) for u in self.target_units])
        out = {}
        for widen in (1.0, WIDEN):
            lam = self._precision(widen)
            before = self._target_cov(lam[None])[0]
            after = self._target_cov(lam[None] + added)
            out[widen] = (before, after)
        (b, a), (bw, aw) = out[1.0], out[WIDEN]
        sd_b, sd_a = np.sqrt(np.diag(b)), np.sqrt(np.diagonal(a, axis1=1, axis2=2))
        growth_b = np.sqrt(np.diag(bw)) / sd_b
        growth_a = np.sqrt(np.diagonal(aw, axis1=1, axis2=2)) / sd_a
        logdet_b = np.linalg.slogdet(b)[1]
        logdet_a = np.linalg.slogdet(a)[1]
        return Evaluation(self.targets, self.target_units, sd_b * to_display, sd_a * to_display,
                          0.5 * (logdet_b - logdet_a) / np.log(2.0), growth_b <= NOT_IDENTIFIED_GROWTH,
                          growth_a <= NOT_IDENTIFIED_GROWTH)
