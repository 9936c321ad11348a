"""What a design starts from: the exact σ-marginal posterior of every measured reading of its instruments.

The campaign's measured readings of the instruments a design chooses among (:mod:`.design_instruments`) — the ball
bar's runs, the touch probe's, the R-test's — each with its own discrepancy scale (``sigma_model``,
``sigma_model_probe``, ``sigma_model_rtest``) under its prior (learnt elsewhere where given), all scales integrated
out on a grid (:class:`~mtmcal_bayes.inference.marginal.MarginalPosterior` with ``groups``), as ``sample --sampler
exact --data …`` does with the same data.  With the ball bar's readings alone it is the one-scale posterior of
before, the same numbers to the bit; with several scales it is laid over the columns the readings touch and the
deviations (the candidates' terms, untouched, keep their priors and move no target).  A scale whose instrument has
no measured reading is at its prior (:meth:`Now.quantiles`, :meth:`Now.variance`).

The planner's rows (:attr:`.design.Planner.row_instrument`, :attr:`~.design.Planner.y`) carry the readings; the
``data`` a planner is made for comes from :func:`measured_data`.
"""

from __future__ import annotations

import numpy as np

from ..inference.marginal import MarginalPosterior
from ..inference.priors import make_prior
from ..parameters import DATA_INSTRUMENTS
from .design_instruments import SCALE_OF
from .design_timing import SESSION

#: cells per scale of a posterior of three scales (the sampler's 48³ is 8× the work; docs/design.md, "Every
#: instrument": realised sds within 0.6 % of a 32³ grid's); one or two scales: the marginal posterior's defaults
CELLS_OF_THREE = 24


def measured_data(campaign, instruments) -> str:
    """The ``data`` value (:data:`~mtmcal_bayes.parameters.DATA_INSTRUMENTS`) of the measured readings of
    ``instruments``; ``"ballbar"`` where none is measured (a new machine, planned for the data to come).  Probe
    readings the probe model cannot take (a gap of the campaign, :func:`left_out`) are not among them, nor R-test
    readings without the machine's description (the R-test model's chain)."""
    have = {"ballbar": bool(campaign.ballbar.runs),
            "probe": campaign.has_probe_readings() and campaign.probe_gap() is None,
            "rtest": campaign.has_rtest_readings() and campaign.machine.description is not None}
    used = tuple(i for i in SESSION if i in instruments and have[i])
    by = {v: k for k, v in DATA_INSTRUMENTS.items() if v is not None} | {SESSION: "all"}
    return by.get(used, "ballbar")


def left_out(campaign, instruments) -> str | None:
    """The sentence of a design that goes on without the campaign's probe readings (a gap keeps the probe model from
    them: the thesis' first published format's C-axis run naming no stylus), or None."""
    if "probe" in instruments and campaign.has_probe_readings() and (gap := campaign.probe_gap()) is not None:
        return gap.skipped("the touch probe's readings in today's posterior")
    return None


def prior_means(planner) -> np.ndarray:
    """(P,) prior means of the planner's parameters, internal units."""
    return np.array([make_prior(p.name, p.base, p.kind, planner.campaign.priors).mean
                     for p in planner.space.parameters])


def taught_prior(planner, instrument: str):
    """The prior (frozen scipy distribution, mm) of ``instrument``'s discrepancy scale (:mod:`.design_instruments`)."""
    from .scale_priors import scale_prior

    if instrument == "ballbar":
        return planner.sigma_prior()
    return scale_prior(planner.campaign, SCALE_OF[instrument], planner.learnt).frozen()


class Now:
    """The exact σ-marginal posterior of ``planner``'s measured readings (module docstring).

    Attributes
    ----------
    scales : the instruments with measured readings, in session order (the ball bar first)
    posterior : the :class:`MarginalPosterior` (None: nothing measured)
    y : (m,) the readings, mm
    cols : the planner's columns the posterior is laid over (a slice: all of them)
    """

    def __init__(self, planner):
        self.planner = planner
        self.y = planner.y
        self.scales = [i for i in SESSION if i in set(planner.row_instrument)]
        self.cols = slice(None)
        if not self.scales:
            self.posterior = None
        elif self.scales == ["ballbar"]:  # the one-scale posterior of the ball bar's data, as it always was
            self.y = planner.observations.mean
            self.posterior = MarginalPosterior(planner.A, planner.V - planner.sigma_model**2, planner.prior_var,
                                               planner.sigma_prior(), prior_mean=prior_means(planner), y=self.y)
        else:
            self.cols = np.flatnonzero(np.any(planner.A != 0.0, axis=0) | planner.is_deviation)
            groups = np.array([self.scales.index(i) for i in planner.row_instrument], dtype=int)
            self.posterior = MarginalPosterior(
                planner.A[:, self.cols], planner.base_var, planner.prior_var[self.cols],
                [taught_prior(planner, i) for i in self.scales], prior_mean=prior_means(planner)[self.cols],
                y=self.y, groups=groups, cells=CELLS_OF_THREE if len(self.scales) >= 3 else None)

    # ------------------------------------------------------------------ targets
    def target_moments(self, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean and sd ``(t,)`` each of the targets ``T @ θ`` (``T`` (t, P) over the planner's columns),
        internal units; nothing measured: the prior's."""
        if self.posterior is None:
            return T @ prior_means(self.planner), np.sqrt((T**2) @ self.planner.prior_var)
        mean, sd = self.posterior.target_moments(self.y[None], T[:, self.cols])
        return mean[0], sd[0]

    def cell_target_var(self, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each grid cell's posterior weight ``(G,)`` and σ-conditional variance of the targets ``(G, t)``."""
        post = self.posterior
        w = post.weights(self.y[None])[:, 0]
        if self.scales == ["ballbar"]:
            return w, np.einsum("tp,gpq,tq->gt", T, post.cov, T)
        Tc = T[:, self.cols]
        out = np.empty((len(w), len(Tc)))
        step = 1024  # cells at a time: a factor each (P² floats), not the whole grid's covariances at once
        for a in range(0, len(w), step):
            C, _ = post.cov_factors(np.arange(a, min(a + step, len(w))))  # C Cᵀ = Σ of each cell
            out[a:a + step] = np.sum((Tc @ C) ** 2, axis=-1)
        return w, out

    # ------------------------------------------------------------------ scales
    def marginal(self, instrument: str) -> tuple[np.ndarray, np.ndarray]:
        """The posterior of ``instrument``'s scale on its grid: weights of its cells ``(n,)`` and their edges
        ``(n + 1,)``, mm (it must have measured readings)."""
        k = self.scales.index(instrument)
        post = self.posterior
        w = post.weights(self.y[None])[:, 0]
        shape = tuple(len(e) - 1 for e in post.edges)
        if len(shape) > 1:
            w = w.reshape(shape).sum(axis=tuple(j for j in range(len(shape)) if j != k))
        return w, post.edges[k]

    def quantiles(self, instrument: str, levels) -> np.ndarray:
        """``instrument``'s scale (mm) at ``levels`` of its current distribution: its posterior where it has
        measured readings, else its prior."""
        if instrument not in self.scales:
            prior = taught_prior(self.planner, instrument)
            return np.array([float(prior.ppf(q)) for q in levels])
        w, edges = self.marginal(instrument)
        cdf = np.concatenate([[0.0], np.cumsum(w)])
        return np.interp(levels, cdf / cdf[-1], edges)

    def variance(self, instrument: str) -> float:
        """The variance of ``instrument``'s scale today (mm²): its posterior's, else its prior's."""
        if instrument not in self.scales:
            return float(taught_prior(self.planner, instrument).var())
        k = self.scales.index(instrument)
        w = self.posterior.weights(self.y[None])[:, 0]
        s = self.posterior.sigma[:, k]
        return float(w @ s**2 - (w @ s) ** 2)


def now_of(planner) -> Now:
    """The planner's :class:`Now`, made once (a planner valuing other candidates, :meth:`.design.Planner.extended`,
    makes its own)."""
    now = getattr(planner, "_now", None)
    if now is None or now.planner is not planner:
        now = Now(planner)
        planner._now = now
    return now


__all__ = ["CELLS_OF_THREE", "Now", "left_out", "measured_data", "now_of", "prior_means", "taught_prior"]
