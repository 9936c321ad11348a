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

What the data teach about ``sigma_model`` itself (:meth:`Planner.sigma_information`):
the means are marginally ``N(A μ0, C(σ))`` with ``C = A Σ0 Aᵀ + N(σ)``, ``N`` the
noise covariance (diagonal ``base_var + σ²``), so the Fisher information about σ is
``I(σ) = ½ tr(C⁻¹ ∂C C⁻¹ ∂C) = 2σ² tr(C⁻²)`` (``∂C/∂σ = 2σ·1``).  Directions of
the data that the parameters can follow (the column space of ``A`` under weak
priors) carry almost none of it: only means beyond what the parameters absorb
(redundant runs) do.  The posterior variance of σ is taken as
``1/(1/var_prior + I(σ0))`` (Laplace approximation), its contraction
``1 − var_post/var_prior = var_prior·I/(1 + var_prior·I)``: 0.5 once ``I``
equals the prior precision.  Under a σ_model prior learnt elsewhere (a fleet of the machine type,
:class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior`) ``var_prior`` is the learnt prior's, and the contraction is
measured against the wider of the assumed and the learnt prior (:meth:`Planner.contraction_reference`):
``1 − var_post/max(var_assumed, var_learnt)``, so that a learnt prior narrower than the assumption counts as
knowledge of σ_model and a wider one is narrowed by the data as the assumed one would be (docs/design.md).  A
candidate run ``k`` times means ``k`` runs of it at its setup, the second and later ones each on its own W-ball
placement (own mount offsets, as the campaign format requires of a second run of one pattern, setup and mount);
more repeats of an existing run add no mean, so no degree of freedom about σ.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from .. import units
from ..campaign import Run
from ..errors import ParameterError
from ..inference.analytic import NOT_IDENTIFIED_GROWTH, WIDEN
from ..inference.identifiability import CENTRED, identifiability
from ..inference.likelihood import GaussianMeanLikelihood
from ..inference.log_posterior import parameter_space
from ..inference.priors import make_prior
from ..io.machine_reader import description_of
from ..machines.deviations import generated, quantities
from ..machines.patterns import components
from ..machines.plugins import provided
from ..machines.selection import redundant
from ..models import build_model, check_data, check_model, jacobian_at_zero, models_of
from ..observations import Observations
from ..parameters import ParameterSpace, data_instruments, weights
from .candidates import Candidate
from .chain_candidates import arc_of
from .probe_catalogue import ProbeCandidate
from .rtest_catalogue import RTestCandidate
from .scale_priors import contraction_reference, default_sigma_model, scale_prior

#: a candidate that changes no target's sd by this fraction identifies nothing new
MIN_GAIN = 0.01
#: the posterior of sigma_model "differs from its prior" once its variance is below (1 − this) of the prior's
SIGMA_CONTRACTION = 0.5
#: most runs of one candidate counted towards :data:`SIGMA_CONTRACTION`
MAX_RUNS = 50


def quantity_table(campaign) -> dict:
    """The quantities of ``campaign``'s machine by name: its plug-in's table where it has one (deviations and derived
    quantities, the thesis' ``dx_CZ_minus_dx_BT``), else its description's deviations."""
    return provided(campaign.machine, "quantity_table") or quantities(campaign.machine.description)


def planned_deviations(campaign) -> list[str]:
    """The deviations a posterior of ``campaign`` samples (the machine's parameter space), in its order."""
    return [p.name for p in parameter_space(campaign, False, "ballbar").parameters if p.group == "deviation"]


def target_names(targets, campaign) -> list[str]:
    """``targets`` as the machine's quantity names (ISO symbols accepted where the machine names them otherwise),
    without repeats: the quantities its plug-in reports (the thesis' eight) and every deviation it samples; a
    ParameterError names an unknown one."""
    devs = planned_deviations(campaign)
    reported = list(provided(campaign.machine, "reported_quantities", ()))
    allowed = reported + [d for d in devs if d not in reported]
    by = {n: n for n in allowed} | {s: n for s, n in provided(campaign.machine, "aliases", ()) if n in allowed}
    why = redundant(description_of(campaign.machine))
    left = {d.name: why[d.name] for d in generated(description_of(campaign.machine)) if d.name in why} | \
        {d.symbol: why[d.name] for d in generated(description_of(campaign.machine)) if d.name in why}
    for t in targets:
        if t not in by:
            reason = f"{t!r} is not estimated on this machine ({left[t]})" if t in left else \
                f"unknown quantity {t!r} for this machine"
            raise ParameterError("targets", f"{reason} (expected one of: {', '.join(allowed)})")
    return list(dict.fromkeys(by[t] for t in targets))


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


def sigma_contraction(fisher, prior_var: float, reference_var: float | None = None):
    """``1 − var_post/var_prior`` of sigma_model with ``var_post = 1/(1/var_prior + fisher)`` (Laplace); with
    ``reference_var`` (under a learnt prior, the wider prior's variance, :meth:`Planner.contraction_reference`)
    ``1 − var_post/reference_var``.  ``fisher`` any shape (1/mm²), variances mm²."""
    x = prior_var * np.asarray(fisher, dtype=float)
    if reference_var is None:
        return x / (1.0 + x)
    return 1.0 - prior_var / (1.0 + x) / reference_var


def trace_inv_sq(M1: np.ndarray, M2: np.ndarray, M3: np.ndarray, t) -> np.ndarray:
    """``tr(C⁻²)`` of ``C = X Xᵀ + N`` (batched over leading axes) from ``Mj = Xᵀ N⁻ʲ X`` and ``t = tr(N⁻²)``.

    ``X`` is the design in prior-sd units (the prior of its parameters standard normal).  Woodbury:
    ``C⁻¹ = N⁻¹ − N⁻¹ X S Xᵀ N⁻¹`` with ``S = (1 + M1)⁻¹``, so
    ``tr(C⁻²) = t − 2 tr(S M3) + tr(S M2 S M2)``: matrices of the parameters' size, whatever the number of means.
    """
    S = np.linalg.inv(np.eye(M1.shape[-1]) + M1)
    G = S @ M2
    out = t - 2.0 * np.einsum("...ij,...ji->...", S, M3) + np.einsum("...ij,...ji->...", G, G)
    return np.maximum(out, 0.0)


def _moments(X: np.ndarray, N_inv: np.ndarray) -> tuple[np.ndarray, ...]:
    """``(Xᵀ N⁻¹ X, Xᵀ N⁻² X, Xᵀ N⁻³ X, tr N⁻²)`` for one block of means with inverse noise covariance ``N_inv``."""
    N2 = N_inv @ N_inv
    return X.T @ N_inv @ X, X.T @ N2 @ X, X.T @ (N2 @ N_inv) @ X, float(np.trace(N2))


@dataclass
class SigmaInformation:
    """What the data would teach about sigma_model (Laplace approximation, see the module docstring).

    ``sigma`` the value it is evaluated at and ``prior_var`` the variance of its prior (mm, mm²);
    ``fisher_now`` (1/mm²) and ``contraction_now`` of the campaign as it is; ``fisher`` (K, R) after
    1..R runs of each candidate; ``contraction`` (K,) after one run; ``runs_needed`` (K,) the fewest runs
    whose contraction reaches :data:`SIGMA_CONTRACTION`, 0 where R runs do not; ``reference_var`` (mm²) the
    variance the contraction is measured against when it is not the prior's (a learnt prior: the wider one's).
    """

    sigma: float
    prior_var: float
    fisher_now: float
    contraction_now: float
    fisher: np.ndarray
    contraction: np.ndarray
    runs_needed: np.ndarray
    reference_var: float | None = None


class Planner:
    """The current closed-form posterior of a campaign and the rows of candidate runs, on any machine.

    What depends on the machine is asked of it: its parameter space (the deviations its posterior samples,
    :func:`~mtmcal_bayes.inference.log_posterior.parameter_space`, with the nuisance terms of every set-up and mount,
    the candidates' too, and of the probe), its quantity table and the weights of each target over the deviations
    (:func:`~mtmcal_bayes.parameters.weights`: the thesis' ``dx_CZ_minus_dx_BT`` is two), the rows of a campaign
    (its model from :func:`~mtmcal_bayes.models.build_model`, linearised at zero where it is not linear) and a
    candidate as a campaign run (its arc and held axes where it has them).

    Parameters
    ----------
    campaign : Campaign
    candidates : list of Candidate or ProbeCandidate (their new setups, mounts and probe terms join the
        parameter space)
    targets : quantity names or ISO symbols (:func:`target_names`); by default the quantities the machine's plug-in
        reports (the thesis' eight of Table 4.5), else the deviations the campaign plus every candidate determine one
        by one (:func:`~mtmcal_bayes.inference.identifiability.identifiability` of their stacked rows, the T ball
        centred), the others named in :attr:`not_targeted`
    sigma_model : fixed model-discrepancy sd of the ball bar, mm (default :func:`default_sigma_model`); the probe's
        is the rms of the ``sigma_model_probe`` prior
    model : one of the machine's models (:func:`~mtmcal_bayes.models.models_of`)
    data : what the campaign's current posterior rests on (a value of :data:`~mtmcal_bayes.models.DATA`):
        ``"ballbar"`` (default), ``"probe"``, ``"both"``, the R-test's (``"rtest"``, ``"ballbar+rtest"``, ...) or
        ``"all"``; each instrument's rows with its own discrepancy scale at the rms of its prior
    sigma_prior : a :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior` learnt elsewhere, or None (the assumed
        priors): the prior of each scale it names, so the default ``sigma_model`` and the probe's scale are the rms
        of the learnt priors, and σ_model's prior is the learnt one wherever it is used (:meth:`sigma_prior`);
        kept as :attr:`learnt` (:mod:`.scale_priors` states it in outputs)
    """

    def __init__(self, campaign, candidates: list, targets=None, *, sigma_model: float | None = None,
                 model: str = "linear", data: str = "ballbar", sigma_prior=None):
        self.campaign = campaign
        self.model = check_model(model, models_of(campaign.machine))
        # a new machine (set-ups and mounts only) is planned for ball-bar data still to come
        self.data = check_data(data, campaign) if campaign.ballbar.runs or data != "ballbar" else data
        self.candidates = list(candidates)
        self._rows_cache: list | None = None
        self.not_targeted: list[str] = []
        self._scales(campaign, sigma_model, sigma_prior)
        bb = campaign.ballbar
        self._setups, self._mounts = dict(bb.setups), dict(bb.mounts)
        for c in self.candidates:
            if isinstance(c, Candidate):
                self._setups.setdefault(c.setup.id, c.setup)
                self._mounts.setdefault(c.mount.id, c.mount)
        self.table = quantity_table(campaign)
        own = parameter_space(campaign, False, data)
        self.deviations = [p.name for p in own.parameters if p.group == "deviation"]
        self._own_terms = ([(p.owner, p.base) for p in own.parameters if p.group == "probe"],
                           [(p.owner, p.base) for p in own.parameters if p.group == "rtest"])
        self._lay_out()
        obs = Observations.from_campaign(campaign)
        self.observations = obs
        self.pooled_sd = obs.pooled_sd()
        A, V, y, of = [np.zeros((0, len(self.space)))], [np.zeros(0)], [np.zeros(0)], []
        used = data_instruments(self.data, campaign)
        if "ballbar" in used and len(obs):  # the ball bar's rows first: repeats of its runs index them
            A.append(self.rows_for(campaign, self.space))
            V.append(GaussianMeanLikelihood(obs, bb.accuracy).base_var + self.sigma_model**2)
            y.append(obs.mean)
            of += ["ballbar"] * len(obs)
        for instrument, scale in (("probe", self.sigma_probe), ("rtest", self.sigma_rtest)):
            if instrument in used:
                part = build_model(self.model, campaign, self.space, instrument)
                A.append(_first_order(part))
                V.append(part.observations.noise_variance() + scale**2)
                y.append(part.observations.mean)
                of += [instrument] * len(part.observations.mean)
        self.A, self.V = np.vstack(A), np.concatenate(V)
        #: (m,) the measured readings (mm) and the instrument of each row of :attr:`A`
        self.y, self.row_instrument = np.concatenate(y), np.array(of, dtype=object)
        self.targets = target_names(targets, campaign) if targets else self._default_targets()
        self.T = self.target_matrix(self.space)
        self.target_units = [self.table[t].unit for t in self.targets]

    def _lay_out(self) -> None:
        """The parameters of the campaign's own terms and the candidates' (:meth:`_make_space`), their prior
        variances and which are deviations."""
        self.space = self._make_space(*self._own_terms)
        rtest = self.campaign.rtest
        stated = rtest.prior_sds() if rtest is not None else None
        priors = [make_prior(p.name, p.base, p.kind, self.campaign.priors, stated=stated)
                  for p in self.space.parameters]
        self.prior_var = np.array([p.sd for p in priors]) ** 2
        self.is_deviation = np.array([p.group == "deviation" for p in self.space.parameters])

    def extended(self, candidates: list) -> Planner:
        """This planner (its campaign, data, scales and targets) valuing ``candidates`` instead: the campaign's own
        rows kept, laid over the parameters the new candidates add (their set-ups' and mounts' terms, zero in the
        campaign's rows) and without those only this planner's candidates had, not made again."""
        new = copy.copy(self)
        new.candidates, new._rows_cache = list(candidates), None
        new._setups, new._mounts = dict(self._setups), dict(self._mounts)
        for c in new.candidates:
            if isinstance(c, Candidate):
                new._setups.setdefault(c.setup.id, c.setup)
                new._mounts.setdefault(c.mount.id, c.mount)
        new._lay_out()
        # the columns of this planner's own candidates' terms (no row of the campaign's touches them) are left out
        kept = set(new.space.names)
        old = [j for j, n in enumerate(self.space.names) if n in kept]
        new.A = np.zeros((len(self.A), len(new.space)))
        new.A[:, [new.space.index(self.space.names[j]) for j in old]] = self.A[:, old]
        new.T = new.target_matrix(new.space)
        return new

    def _make_space(self, probe: list, rtest: list = ()) -> ParameterSpace:
        """The parameters: the machine's deviations, every set-up's and mount's terms (the candidates' too), the
        probe's own terms ``probe`` (with probe data) and each probe candidate's, the R-test's ``rtest`` (with R-test
        data) and each R-test candidate's (a placement and a nest they share, once)."""
        probe = probe + [t for c in self.candidates if isinstance(c, ProbeCandidate) for t in c.terms(self.campaign)]
        rtest = list(dict.fromkeys(list(rtest) + [t for c in self.candidates if isinstance(c, RTestCandidate)
                                                   for t in c.terms(self.campaign)]))
        return ParameterSpace(list(self._setups), list(self._mounts), self.deviations, probe, table=self.table,
                              rtest=rtest)

    def _default_targets(self) -> list[str]:
        """The quantities the machine's plug-in reports, else those the campaign and every candidate determine."""
        reported = provided(self.campaign.machine, "reported_quantities")
        return target_names(reported, self.campaign) if reported else self._determinable()

    def _determinable(self) -> list[str]:
        """The deviations the campaign and every candidate together determine one by one (the rest in
        :attr:`not_targeted`)."""
        rows = [A for A, _ in self.candidate_rows()] if self.candidates else []
        J = np.vstack([self.A] + rows)
        if not len(J):
            self.not_targeted = list(self.deviations)
            return []
        known = [b for b in CENTRED if any(p.base == b for p in self.space.parameters)]
        determined = set(identifiability(J, self.space, known=known).determined)
        self.not_targeted = [d for d in self.deviations if d not in determined]
        return [d for d in self.deviations if d in determined]

    def _scales(self, campaign, sigma_model: float | None, sigma_prior) -> None:
        """The learnt prior kept, the ball bar's fixed σ_model (default the rms of its prior) and the probe's."""
        self.learnt = sigma_prior
        self.sigma_model = default_sigma_model(campaign, learnt=sigma_prior) if sigma_model is None \
            else float(sigma_model)
        self.sigma_probe = default_sigma_model(campaign, "sigma_model_probe", sigma_prior)
        self.sigma_rtest = default_sigma_model(campaign, "sigma_model_rtest", sigma_prior)

    def fixed_scale(self, instrument: str) -> float:
        """The fixed discrepancy scale (mm) of ``instrument``'s rows: the ball bar's :attr:`sigma_model`, the others'
        the rms of their priors."""
        return {"ballbar": self.sigma_model, "probe": self.sigma_probe, "rtest": self.sigma_rtest}[instrument]

    @property
    def base_var(self) -> np.ndarray:
        """(m,) the variance of each measured reading without its discrepancy scale, mm²."""
        fixed = np.array([self.fixed_scale(i) for i in self.row_instrument], dtype=float)
        return self.V - fixed**2

    @property
    def own_terms(self) -> tuple[list, list]:
        """The probe's and the R-test's own terms of the measured readings ``(owner, base)`` (with their data)."""
        return self._own_terms

    def retarget(self, targets: list[str]) -> None:
        """Value ``targets`` instead (names checked as at construction; the rows are kept)."""
        self.targets = target_names(targets, self.campaign)
        self.T = self.target_matrix(self.space)
        self.target_units = [self.table[t].unit for t in self.targets]

    # ------------------------------------------------------------------ what depends on the machine
    def target_matrix(self, space: ParameterSpace) -> np.ndarray:
        """``T`` (t, P): each target's deviation weights over ``space``."""
        T = np.zeros((len(self.targets), len(space)))
        for i, t in enumerate(self.targets):
            for name, w in weights(t).items():
                T[i, space.index(name)] = w
        return T

    def space_for(self, campaign) -> ParameterSpace:
        """The ball-bar parameter space of ``campaign`` (its set-ups and mounts, the planner's deviations)."""
        bb = campaign.ballbar
        return ParameterSpace(list(bb.setups), list(bb.mounts), self.deviations, table=self.table)

    def rows_for(self, campaign, space: ParameterSpace) -> np.ndarray:
        """Rows ``(m, P)`` of ``campaign``'s ball-bar runs over ``space``: the planner's model, linearised at zero
        where it is not linear, differentiated in the columns the runs touch only (the deviations, their set-ups'
        and mounts' terms; the other columns are zero)."""
        bb = campaign.ballbar
        if not bb.runs:
            return np.zeros((0, len(space)))
        used = ParameterSpace(list(dict.fromkeys(r.setup for r in bb.runs)),
                              list(dict.fromkeys(r.mount for r in bb.runs)), self.deviations, table=self.table)
        own = _first_order(build_model(self.model, campaign, used))
        out = np.zeros((len(own), len(space)))
        out[:, [space.index(n) for n in used.names]] = own
        return out

    def as_run(self, candidate: Candidate) -> Run:
        """A new-run candidate as a campaign run (zero readings, ``repeats`` each: rows do not depend on them), with
        its arc and held axes where it has them."""
        machine = self.campaign.machine
        comps = provided(machine, "pattern_components") or (lambda p: components(machine.description, p))
        arc = None if candidate.arc_deg is None else arc_of(candidate, machine.description)
        return Run(candidate.pattern, candidate.setup.id, candidate.mount.id,
                   {comp: np.zeros(candidate.repeats) for comp in comps(candidate.pattern)},
                   arc_deg=arc, hold_deg=dict(candidate.hold_deg) or None)

    # ------------------------------------------------------------------ rows
    def noise_var(self, repeats: int) -> float:
        """Variance of one repeat mean of a new run, mm²."""
        return self.pooled_sd**2 / repeats + self.campaign.ballbar.accuracy**2 + self.sigma_model**2

    def candidate_rows(self, candidates: list | None = None) -> list[tuple[np.ndarray, np.ndarray]]:
        """For each candidate, its rows ``(k, P)`` and precision weights ``(k,)`` (1/mm²); the planner's own
        candidates' rows made once."""
        if candidates is None or _same(candidates, self.candidates):
            if self._rows_cache is None:
                self._rows_cache = self._rows_of_each(self.candidates)
            return self._rows_cache
        return self._rows_of_each(candidates)

    def _rows_of_each(self, candidates: list) -> list[tuple[np.ndarray, np.ndarray]]:
        """:meth:`_rows_of` of each candidate, the new runs' at one mount, one bar length and one set-up from one
        model of them all (:meth:`_new_runs_rows`: a catalogue's hundreds of runs in a few models, not one model
        each)."""
        out: list = [None] * len(candidates)
        groups: dict[tuple, list[int]] = {}
        for i, c in enumerate(candidates):
            # one set-up: each set-up's terms are columns the model differentiates every run's rows in, and at a mount
            # the campaign has not measured the first run there places the W ball for the others (at its set-up's
            # tool length: the same placement as each run's own)
            if isinstance(c, Candidate) and c.repeat_of is None:
                groups.setdefault((c.mount.id, c.length, c.setup.id), []).append(i)
            else:
                out[i] = self._rows_of(c)
        for idx in groups.values():
            for i, rows in zip(idx, self._new_runs_rows([candidates[i] for i in idx])):
                out[i] = rows
        return out

    def _rows_of(self, c) -> tuple[np.ndarray, np.ndarray]:
        if isinstance(c, ProbeCandidate):
            A, base = c.rows(self.campaign, self.space, self.deviations, self.table)
            return A, 1.0 / (base + self.sigma_probe**2)
        if isinstance(c, RTestCandidate):
            A, base = c.rows(self.campaign, self.space, self.deviations, self.table)
            return A, 1.0 / (base + self.sigma_rtest**2)
        return self._new_runs_rows([c])[0] if c.repeat_of is None else self._repeat_rows(c)

    def _repeat_rows(self, c: Candidate):
        keys = [j for j, k in enumerate(self.observations.keys) if k.run == c.repeat_of]
        n = self.observations.n[keys]
        s2 = np.where(n > 1, np.nan_to_num(self.observations.sd[keys]) ** 2, self.pooled_sd**2)
        v_new = self.V[keys] - s2 / n + s2 / (n + c.repeats)
        return self.A[keys], 1.0 / v_new - 1.0 / self.V[keys]

    def _new_runs_rows(self, cands: list[Candidate]) -> list[tuple[np.ndarray, np.ndarray]]:
        """Rows and weights of each new run of ``cands`` (one mount, one bar length, one set-up), from a campaign of
        those runs after the campaign's first run at their mount: a model that places a mount's W ball by the first run there
        (the chain: that run's set-up enters the rows of every run at the mount) sees each candidate where the
        campaign placed it; one that does not, the same rows as in the campaign itself.  After that first run a
        run's rows depend on its own set-up and mount alone, so several runs share one model; at a mount the
        campaign has not measured, the first of them places the W ball for the others, at the set-up they share,
        where each would place it alone (the same rows, to the bit, on every built-in type's catalogue)."""
        c0 = cands[0]
        first = next((r for r in self.campaign.ballbar.runs if r.mount == c0.mount.id), None)
        aug = copy.copy(self.campaign)
        bb = copy.copy(self.campaign.ballbar)
        bb.length = c0.length
        bb.setups, bb.mounts = self._setups, self._mounts
        before = [] if first is None else [first]
        bb.runs = before + [self.as_run(c) for c in cands]
        aug.ballbar = bb
        design = self.rows_for(aug, self.space)
        run_of = np.array([k.run for k in Observations.from_campaign(aug).keys])
        rows = [design[run_of == len(before) + j] for j in range(len(cands))]
        return [(A, np.full(len(A), 1.0 / self.noise_var(c.repeats))) for A, c in zip(rows, cands)]

    # ------------------------------------------------------------------ posterior
    def _precision(self, widen: float = 1.0) -> np.ndarray:
        var0 = self.prior_var * np.where(self.is_deviation, widen**2, 1.0)
        return np.diag(1.0 / var0) + self.A.T @ (self.A / self.V[:, None])

    def _target_cov(self, precisions: np.ndarray) -> np.ndarray:
        """``T Λ⁻¹ Tᵀ`` (K, t, t) of the precisions ``Λ`` (K, p, p): solved for the t targets' columns only, not
        inverted (a third of the work where t ≪ p)."""
        rhs = np.broadcast_to(self.T.T, precisions.shape[:-2] + self.T.T.shape)
        return self.T @ np.linalg.solve(precisions, rhs)

    def evaluate(self, candidates: list[Candidate] | None = None, *, rows=None) -> Evaluation:
        """Expected target sds, information gain and identifiability after each candidate (``rows``: their
        :meth:`candidate_rows`, if already made)."""
        candidates = self.candidates if candidates is None else candidates
        rows = self.candidate_rows(candidates) if rows is None else rows
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

    # ------------------------------------------------------------------ sigma_model
    def sigma_prior(self):
        """The prior of sigma_model (frozen scipy distribution, mm): learnt elsewhere, else the campaign's."""
        return scale_prior(self.campaign, "sigma_model", self.learnt).frozen()

    def contraction_reference(self) -> float | None:
        """The variance σ_model's contraction is measured against, mm² (:func:`.scale_priors.contraction_reference`):
        None (its prior's) without a learnt prior, the wider of the assumed and the learnt prior's under one."""
        return contraction_reference(self.campaign, self.learnt)

    def sigma_information(self, candidates: list[Candidate] | None = None, *, rows=None,
                          max_runs: int = MAX_RUNS) -> SigmaInformation:
        """Fisher information about sigma_model at :attr:`sigma_model` and the contraction of its posterior,
        today and after 1..``max_runs`` runs of each candidate (``rows``: their :meth:`candidate_rows`).

        Computed in the parameters' coordinates (prior-sd units), restricted to the parameters the data
        touch: one small batched inverse per candidate for all run counts.
        """
        if max_runs < 1:
            raise ValueError(f"max_runs must be at least 1, got {max_runs}")
        candidates = self.candidates if candidates is None else candidates
        rows = self.candidate_rows(candidates) if rows is None else rows
        prior_var = float(self.sigma_prior().var())
        ref = self.contraction_reference()
        if self.data != "ballbar":  # the formula below holds for one scale on every row (docs/planning.md)
            zero = np.zeros((len(candidates), max_runs))
            return SigmaInformation(self.sigma_model, prior_var, 0.0, 0.0, zero, zero[:, 0], np.zeros(len(candidates),
                                                                                                     dtype=int), ref)
        scale = np.sqrt(self.prior_var)
        X0 = self.A * scale
        used = np.any(X0 != 0.0, axis=0)
        now = 2.0 * self.sigma_model**2 * float(trace_inv_sq(*_moments(X0[:, used], np.diag(1.0 / self.V))))
        runs = np.arange(1, max_runs + 1)
        fisher = np.zeros((len(candidates), max_runs))
        for k, (c, (B, w)) in enumerate(zip(candidates, rows)):
            if isinstance(c, (ProbeCandidate, RTestCandidate)):  # their own scales: nothing about sigma_model
                fisher[k] = now
                continue
            if c.repeat_of is None:
                tr = self._trace_new_runs(c, X0, B * scale, noise=1.0 / w, runs=runs)
            else:
                tr = self._trace_more_repeats(c, X0[:, used], runs)
            fisher[k] = 2.0 * self.sigma_model**2 * tr
        contraction = sigma_contraction(fisher, prior_var, ref)
        reached = contraction >= SIGMA_CONTRACTION
        needed = np.where(reached.any(axis=1), np.argmax(reached, axis=1) + 1, 0)
        return SigmaInformation(self.sigma_model, prior_var, now, float(sigma_contraction(now, prior_var, ref)), fisher,
                                contraction[:, 0], needed, ref)

    def _trace_new_runs(self, c: Candidate, X0: np.ndarray, Xc: np.ndarray, *, noise: np.ndarray,
                        runs: np.ndarray) -> np.ndarray:
        """``tr(C⁻²)`` (R,) of the campaign plus ``runs`` runs of a new-run candidate (rows ``Xc``, prior-sd units):
        the first as the candidate is, each further one with its own W-ball offsets, integrated out (they add
        ``X_W X_Wᵀ`` to that run's noise covariance)."""
        cols = np.flatnonzero(np.any(X0 != 0.0, axis=0) | np.any(Xc != 0.0, axis=0))
        X0, Xc = X0[:, cols], Xc[:, cols]
        own = np.array([p.group == "mount" and p.owner == c.mount.id for p in
                        (self.space.parameters[j] for j in cols)], dtype=bool)
        Xw = Xc[:, own]
        again = np.where(own[None, :], 0.0, Xc)
        base = _moments(X0, np.diag(1.0 / self.V))
        first = _moments(Xc, np.diag(1.0 / noise))
        more = _moments(again, np.linalg.inv(np.diag(noise) + Xw @ Xw.T))
        n = (runs - 1)[:, None, None]
        M = [b + f + n * m for b, f, m in zip(base[:3], first[:3], more[:3])]
        return trace_inv_sq(*M, base[3] + first[3] + (runs - 1) * more[3])

    def _trace_more_repeats(self, c: Candidate, X0: np.ndarray, runs: np.ndarray) -> np.ndarray:
        """``tr(C⁻²)`` (R,) after ``runs`` times ``c.repeats`` more repeats of run ``c.repeat_of``: no new mean, the
        run's means only lose part of their ``s²/n``."""
        keys = [j for j, k in enumerate(self.observations.keys) if k.run == c.repeat_of]
        n = self.observations.n[keys]
        s2 = np.where(n > 1, np.nan_to_num(self.observations.sd[keys]) ** 2, self.pooled_sd**2)
        V = np.broadcast_to(self.V, (len(runs), len(self.V))).copy()
        V[:, keys] += s2 / (n + runs[:, None] * c.repeats) - s2 / n
        W = 1.0 / V
        M = [np.einsum("mp,rm,mq->rpq", X0, W**j, X0) for j in (1, 2, 3)]
        return trace_inv_sq(*M, np.sum(W**2, axis=1))


def _same(candidates: list, others: list) -> bool:
    """Whether two lists hold the same candidate objects in the same order (the planner keeps a copy of the list it
    was given, which its callers then pass back)."""
    return candidates is others or (len(candidates) == len(others) and all(a is b for a, b in zip(candidates, others)))


def _first_order(model) -> np.ndarray:
    """The rows ``(m, P)`` of ``model``: its design where it is linear, else its Jacobian at zero deviations
    (:func:`~mtmcal_bayes.models.jacobian_at_zero`: by the complex step where the model allows it)."""
    return model.design if hasattr(model, "design") else jacobian_at_zero(model)
