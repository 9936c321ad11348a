"""The exact preposterior of a whole design: what measuring it delivers, σ_model learnt from the data.

Machines are drawn from what is known now — the parameters and the discrepancy scales from the exact σ-marginal
posterior given every measured reading, the ball bar's, the probe's and the R-test's (:mod:`.design_now`;
:class:`~mtmcal_bayes.inference.marginal.MarginalPosterior`), from the priors for a new machine; the new runs' own
nuisance offsets from their priors — the design's
means are simulated with the repeat scatter, the instrument error and σ_model, and the exact
posterior of each simulated campaign gives the realised posterior sd of every target and the realised
posterior variance of σ_model.  Reported: their mean and 10–90 % spread, the share of machines whose
realised sd meets each target, and the expected contraction ``1 − E[var(σ | y)]/var_prior(σ)`` (under a σ_model
prior learnt elsewhere, drawn from and inferred with that prior, and measured against the wider of the assumed
and the learnt prior's variance, :meth:`.design.Planner.contraction_reference`).

For a kinematic model the rows are its Jacobian at zero deviations (the model linearised), as in the
planner; the space, rows and targets are the planner's (:meth:`.design.Planner.rows_for`: on a described machine,
its chain's first order; a probe or R-test run's, the first order of its model through the chain).  Where that
first order misses the machine's kinematics at the drawn machines by more than a stated fraction of the targets (or
the instruments' accuracy), the designed runs' means — every instrument's — are the kinematic models' instead,
inferred with the same linear posterior (:mod:`.design_chain`).  One path for one scale and several: a design of
ball-bar runs is the case of the ball bar's scale alone.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from .. import units
from ..inference.marginal import MarginalPosterior
from ..inference.priors import make_prior
from ..inference.row_reduction import RowReduction
from ..observations import Observations
from ..parameters import ParameterSpace
from .design import Planner
from .design_chain import Kinematics, kinematic_means
from .design_now import CELLS_OF_THREE, taught_prior
from .design_runs import DesignedRun, with_runs
from .design_timing import SESSION

#: simulated machines of the check
N_SIM = 400
#: cells per discrepancy scale of the check's grid, by the number of scales: one, the marginal posterior's own
#: default; two, its 48²; three, 24³ rather than its 48³ (8× fewer cells: each machine's realised sds within 0.6 % of
#: a 32³ grid's, their means within 0.02 %; 16³ was 4.7 % off; docs/design.md, "Every instrument")
CHECK_CELLS = {1: None, 2: 48, 3: 24}


@dataclass
class Preposterior:
    """Realised results over ``n_sim`` simulated machines (display units: ″, µm).

    ``sd`` (n_sim, t) realised posterior sds; ``sd_now`` (t,) the exact posterior sd today;
    ``contraction`` (n_sim,) realised σ_model contraction; ``contraction_now``.
    """

    targets: list[str]
    sd: np.ndarray
    sd_now: np.ndarray
    contraction: np.ndarray
    contraction_now: float
    sigma_mean_um: np.ndarray  # (n_sim,) posterior mean of σ_model per machine
    #: how the machines were measured: through the kinematics or the linear rows (:mod:`.design_chain`)
    kinematics: Kinematics | None = None
    #: (n_sim, P) the simulated machines and (n_sim, m_new) the designed runs' simulated readings, mm
    truth: np.ndarray | None = None
    readings: np.ndarray | None = None
    #: the space of ``truth``'s columns: the deviations and every nuisance term of the designed campaign
    space: ParameterSpace | None = None
    #: (n_sim, s) mm the machines' discrepancy scales, one column per instrument with rows (the ball bar's first)
    scales: np.ndarray | None = None

    @property
    def sd_mean(self) -> np.ndarray:
        return self.sd.mean(axis=0)

    def sd_quantile(self, q: float) -> np.ndarray:
        return np.quantile(self.sd, q, axis=0)

    def share_met(self, targets: np.ndarray) -> np.ndarray:
        """(t,) share of machines whose realised sd meets each target (NaN target: NaN)."""
        tg = np.asarray(targets, float)
        out = np.mean(self.sd <= np.where(np.isfinite(tg), tg, np.inf), axis=0)
        return np.where(np.isfinite(tg), out, np.nan)

    def share_all_met(self, targets: np.ndarray) -> float:
        """Share of machines whose realised sds meet every target."""
        tg = np.where(np.isfinite(targets), targets, np.inf)
        return float(np.mean(np.all(self.sd <= tg, axis=1)))


def preposterior(planner: Planner, runs: list[DesignedRun], *, n_sim: int = N_SIM, seed: int | None = 0,
                 taught: str = "ballbar", targets: np.ndarray | None = None,
                 through: bool | None = None) -> Preposterior:
    """Simulate measuring ``runs`` after ``planner``'s campaign on ``n_sim`` machines (see the module docstring).

    Touch-probe and R-test runs among ``runs`` carry their own discrepancy scales: each simulated machine draws
    every scale from its prior (a measured instrument's, with the parameters, from today's posterior: every measured
    reading is in it and in each simulated campaign's posterior), and the
    exact posterior integrates all of them out on a grid of :data:`CHECK_CELLS` cells per scale; ``taught`` the
    instrument whose scale's contraction is reported (:mod:`.design_instruments`; where it has no rows, the first
    scale's).  The designed runs — ball bar, probe and R-test — are measured through the machine's kinematics where
    the linear model's misfit is large against ``targets`` (t,) (display units, NaN: none) or the instruments'
    accuracy, or as ``through`` forces (:func:`.design_chain.kinematic_means`)."""
    rng = np.random.default_rng(seed)
    campaign = planner.campaign
    if campaign.ballbar.runs and "ballbar" not in set(planner.row_instrument):
        # the ball bar's readings are not in today's posterior (a design without the ball bar): nor are its runs here
        campaign = copy.copy(campaign)
        campaign.ballbar = copy.copy(campaign.ballbar)
        campaign.ballbar.runs = []
    aug = with_runs(campaign, runs, planner.as_run)
    others = [r.measured for r in runs if r.instrument != "ballbar"]
    measured_other = planner.row_instrument != "ballbar"  # the campaign's probe and R-test readings
    space = planner.space_for(aug)
    if others or measured_other.any():
        own_probe, own_rtest = planner.own_terms
        space = ParameterSpace(list(aug.ballbar.setups), list(aug.ballbar.mounts), planner.deviations,
                               own_probe + [t for c in others if c.instrument == "probe" for t in c.terms(campaign)],
                               table=planner.table,
                               rtest=list(dict.fromkeys(own_rtest + [t for c in others if c.instrument == "rtest"
                                                                     for t in c.terms(campaign)])))
    stated = campaign.rtest.prior_sds() if campaign.rtest is not None else None
    priors = [make_prior(p.name, p.base, p.kind, campaign.priors, stated=stated) for p in space.parameters]
    prior_var = np.array([p.sd for p in priors]) ** 2
    prior_mean = np.array([p.mean for p in priors])
    A = planner.rows_for(aug, space)
    keys = Observations.from_campaign(aug).keys
    m0 = len(campaign.ballbar.runs)
    bar_runs = [r for r in runs if r.instrument == "ballbar"]
    sigma0 = planner.sigma_model
    base_now = planner.base_var
    base_new = [np.array([planner.noise_var(bar_runs[k.run - m0].repeats) - sigma0**2 for k in keys
                          if k.run >= m0])]
    new = np.array([k.run >= m0 for k in keys], dtype=bool)
    instrument = ["ballbar"] * len(A)
    if measured_other.any():  # the measured rows first (the ball bar's, then the others'), then the designed ones
        A = np.vstack([A[~new], _laid_over(planner, measured_other, space), A[new]])
        instrument = list(planner.row_instrument) + ["ballbar"] * int(new.sum())
        new = np.concatenate([np.zeros(len(planner.y), dtype=bool), np.ones(int(new.sum()), dtype=bool)])
    for c in others:
        rows, base = c.rows(campaign, space, planner.deviations, planner.table)
        A = np.vstack([A, rows])
        base_new.append(base)
        instrument += [c.instrument] * len(rows)
    base_new = np.concatenate(base_new)
    new = np.concatenate([new, np.ones(len(A) - len(new), dtype=bool)])
    scales = [i for i in SESSION if i in instrument] or ["ballbar"]  # the scales with rows, the ball bar's first
    groups = np.array([scales.index(i) for i in instrument], dtype=int)
    T = planner.target_matrix(space)
    sigma_prior = planner.sigma_prior()
    # the grid of the simulated campaigns' posteriors: the prior's range, widened to where the measured data put σ
    lo, hi = float(sigma_prior.ppf(1e-5)), float(sigma_prior.ppf(0.99999))
    own = {i: taught_prior(planner, i) for i in scales}
    highs = {i: float(own[i].ppf(0.99999)) for i in scales if i != "ballbar"}
    y_now = planner.y
    measured = [i for i in SESSION if i in set(planner.row_instrument)]  # the scales of today's posterior
    if measured:
        now = _now_posterior(planner, A[~new], base_now, prior_var=prior_var, prior_mean=prior_mean, y=y_now,
                             measured=measured)
        theta, sigma = now.draw(y_now, n_sim, rng)
        drawn = {i: sigma[:, k] for k, i in enumerate(measured)}  # each measured scale from today's posterior
        sigma = drawn.get("ballbar")
        _, sd_now = now.target_moments(y_now[None], T)
        w_now = now.weights(y_now[None])[:, 0]
        var_now = float(sigma_prior.var())  # the ball bar's scale at its prior where it has no measured reading
        var_of = {}  # each measured scale's variance today
        for k, i in enumerate(measured):
            var_i = w_now @ now.sigma[:, k] ** 2 - (w_now @ now.sigma[:, k]) ** 2
            top = min(max(highs.get(i, hi), float(now.edges[k][-1])), float(taught_prior(planner, i).support()[1]))
            if i == "ballbar":
                var_now, hi = var_i, top
            else:
                highs[i] = top
            var_of[i] = var_i
    else:
        var_of = {}
        theta = np.column_stack([p.draw(n_sim, rng) for p in priors])
        sigma = stratified_draws(sigma_prior, n_sim, rng)
        drawn = {"ballbar": sigma}
        sd_now = np.sqrt(np.sum(T**2 * prior_var, axis=1))[None]
        var_now = float(sigma_prior.var())
    draws = {i: (drawn[i] if i in drawn else stratified_draws(own[i], n_sim, rng)) for i in scales}
    per_row = np.column_stack([draws[i] for i in scales])[:, groups[new]]  # (n_sim, new rows)
    means, kinematics = kinematic_means(planner, aug, theta, A, new=new, space=space, others=others,
                                        instrument=instrument, targets=targets, through=through)
    y_new = means + rng.standard_normal(per_row.shape) * np.sqrt(base_new[None] + per_row**2)
    y_all = np.hstack([np.broadcast_to(y_now, (n_sim, len(y_now))), y_new])
    lows = [lo if i == "ballbar" else float(own[i].ppf(1e-5)) for i in scales]
    # the simulated campaigns' posteriors: the rows of one run kind reduced to their rank (the same posterior)
    rows = RowReduction(A, np.concatenate([base_now, base_new]), groups)
    after = MarginalPosterior(rows.A, rows.base_var, prior_var, [own[i] for i in scales],
                              prior_mean=prior_mean, sigma_min=lows,
                              sigma_max=[hi if i == "ballbar" else highs[i] for i in scales], groups=rows.groups,
                              cells=CHECK_CELLS[min(len(scales), 3)])
    rest = rows.log_rest(y_all - A @ prior_mean, after.sigma)  # (G, n): what the reduction leaves out
    y_all = rows.data(y_all)
    taught = taught if taught in scales else scales[0]  # no row of the taught scale: the first scale's
    s = after.sigma[:, scales.index(taught)]
    if taught != "ballbar":  # the taught scale's variance today: its posterior's where measured, else its prior's
        var_now = var_of[taught] if taught in var_of else float(own[taught].var())
    prior_var_s = (planner.contraction_reference() or float(sigma_prior.var())) if taught == "ballbar" else \
        float(own[taught].var())  # a learnt prior: the wider one's
    _, sd, w = after.target_moments(y_all, T, log_extra=rest, with_weights=True)  # w: (G, n)
    mean_s = s @ w
    var_s = (s**2) @ w - mean_s**2
    scale = np.array([units.from_internal(1.0, u) for u in planner.target_units])
    return Preposterior(list(planner.targets), sd * scale, sd_now[0] * scale, 1.0 - var_s / prior_var_s,
                        float(1.0 - var_now / prior_var_s), units.from_internal(mean_s, "um"), kinematics, theta, y_new,
                        space, np.column_stack([draws[i] for i in scales]))


def stratified_draws(prior, n: int, rng: np.random.Generator) -> np.ndarray:
    """``n`` draws (n,) of a discrepancy scale from its frozen ``prior`` (mm), one in each of ``n`` strata of equal
    prior probability, in random order (Latin hypercube sampling, each scale stratified on its own).

    The realised sds of the targets a design only just meets follow the scale of their instrument almost one to one
    (a correlation of 0.97 on the vertical turn-mill), so the share of machines meeting such a target is the prior
    probability of the scale below a threshold.  Drawn plainly, the check's 400 scales put that share 1.5 points
    (binomial) off on their own, and the search keeps the cheapest design its draws find meeting the promise:
    designs whose draws were kind (docs/design.md, "Every instrument").  Stratified, the scales follow the prior to
    a 400th of probability, and each draw is still from the prior (the estimates stay unbiased)."""
    return np.asarray(prior.ppf((rng.permutation(n) + rng.random(n)) / n), float)


def _laid_over(planner: Planner, rows: np.ndarray, space: ParameterSpace) -> np.ndarray:
    """The planner's measured rows ``rows`` (a mask of :attr:`.design.Planner.A`'s rows) over ``space``'s columns
    (every column they touch is among ``space``'s: the deviations and their instrument's own terms)."""
    A = planner.A[rows]
    out = np.zeros((len(A), len(space)))
    names = set(space.names)
    kept = [j for j, n in enumerate(planner.space.names) if n in names]
    out[:, [space.index(planner.space.names[j]) for j in kept]] = A[:, kept]
    return out


def _now_posterior(planner: Planner, A: np.ndarray, base: np.ndarray, *, prior_var, prior_mean, y: np.ndarray,
                   measured: list[str]) -> MarginalPosterior:
    """Today's exact posterior over the check's columns: the ball bar's one scale as it always was, several scales
    as :class:`.design_now.Now` lays them out (its grid)."""
    if measured == ["ballbar"]:
        return MarginalPosterior(A, base, prior_var, planner.sigma_prior(), prior_mean=prior_mean, y=y)
    groups = np.array([measured.index(i) for i in planner.row_instrument], dtype=int)
    return MarginalPosterior(A, base, prior_var, [taught_prior(planner, i) for i in measured], prior_mean=prior_mean,
                             y=y, groups=groups, cells=CELLS_OF_THREE if len(measured) >= 3 else None)


__all__ = ["Preposterior", "preposterior", "stratified_draws", "N_SIM"]
