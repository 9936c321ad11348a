"""emcee ensembles started where the posterior is and stopped when the user's ESS and R-hat targets hold.

* ``n_ensembles`` (≥ 2, default 4) independent :class:`emcee.EnsembleSampler` runs with
  ``vectorize=True``: one log-density call per move evaluates a whole (half-)ensemble.
  The walkers of one ensemble are not independent chains; the ensembles are, and
  R-hat is computed across them.
* Start: every ensemble draws its walkers from the linearised σ-marginal posterior
  (:class:`~.approximation.PosteriorApproximation`), which for the ``linear`` model
  with normal priors is the posterior itself: there is no start to forget.
* Moves: an independence Metropolis–Hastings move proposing from that
  approximation (weight 0.8) and differential evolution (0.2).  The acceptance
  test keeps the chain exact whatever the approximation; its acceptance rate
  (≈ 0.95 for ``linear``) says how close the approximation is.  Where it is not
  close, DE moves still explore; emcee's DESnookerMove is not used (on a
  24-dimensional standard normal it returned sds of 0.75).
* Stopping: the first check comes after ``min_steps`` steps, later ones where the
  ESS rate predicts the targets are met (at most doubling the run).  At a check
  the burn-in is detected: ⌈2τ⌉ steps (τ the integrated autocorrelation time of the
  gating quantities, from ArviZ's ESS, at least 2), more — a quarter, then a half of the run —
  while R-hat says the first part differs from the rest.  R-hat is ArviZ's
  rank-normalised R-hat over 2K chains, each ensemble split into halves in time,
  so it compares the ensembles with each other and each ensemble's start with its
  end.  The run stops when that R-hat ≤ ``max_rhat`` and ArviZ's bulk and tail ESS
  reach ``target_ess`` for every reported quantity (:func:`_gating`) and
  ``target_ess_sigma`` for each sampled discrepancy scale — or at ``max_steps``, with a warning.
  The checks cost little: a run has a few of them, on chains of tens to hundreds
  of steps.
* Storage is preallocated and grows geometrically; with a checkpoint, emcee's
  HDF5 backend stores every step.  Every decision depends only on the stored chain
  and emcee stores its random state with every step, so a run resumed from its
  checkpoint continues exactly as the uninterrupted run would have.  A checkpoint
  says which posterior and chain settings it holds (:mod:`.checkpoint`); one of
  another is refused before anything is written to it.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import emcee
import numpy as np

from ..arviz_import import az
from ..errors import MtmcalError, ParameterError
from ..parameters import is_scale
from ..progress import Progress, ProgressEvent, emit
from .analytic import reported
from .approximation import PosteriorApproximation
from .checkpoint import claim
from .log_posterior import LogPosterior
from .results import display_draws

#: samplers: emcee ensembles, or independent draws of the exact posterior (linear model, normal priors)
SAMPLERS = ("emcee", "exact")


def check_step_budget(max_steps: int, min_steps: int) -> None:
    """A run is at least ``min_steps`` long: a smaller budget would be overrun silently."""
    if max_steps < min_steps:
        raise ParameterError("max_steps", f"{max_steps} is below the shortest run of {min_steps} steps")


@dataclass
class SamplerSettings:
    """What a run aims for and how.

    ``target_ess``: bulk and tail ESS of each of the eight quantities;
    ``target_ess_sigma``: of sigma_model; ``max_rhat``: R-hat across ensembles and halves;
    ``min_steps``: the first check; ``max_steps``: the budget per ensemble;
    ``independence_weight``: share of independence moves (the rest differential evolution);
    ``sampler``: ``"emcee"`` or ``"exact"`` (independent draws of the exact posterior).
    """

    n_ensembles: int = 4
    n_walkers: int | None = None  # at least 2·q (rounded up to even); default max(96, 2·q)
    target_ess: float = 1000.0
    target_ess_sigma: float = 400.0
    max_rhat: float = 1.01
    min_steps: int = 50
    max_steps: int = 20_000
    independence_weight: float = 0.8
    sampler: str = "emcee"
    seed: int | None = None

    def __post_init__(self):
        if self.n_ensembles < 2:
            raise ParameterError("n_ensembles", "at least two independent ensembles are needed for R-hat "
                                 "(four by default)")
        if self.sampler not in SAMPLERS:
            raise ParameterError("sampler", f"unknown sampler {self.sampler!r} (emcee or exact)")
        for name in ("target_ess", "target_ess_sigma"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ParameterError(name, f"{value} is not a positive number")
        if not 0.0 <= self.independence_weight <= 1.0:
            raise ParameterError("independence_weight", f"{self.independence_weight} is not between 0 and 1")
        check_step_budget(self.max_steps, self.min_steps)

    def moves(self, approximation: PosteriorApproximation):
        w = self.independence_weight
        return [(approximation.independence_move(), w), (emcee.moves.DEMove(), 1.0 - w)]

    def walkers(self, q: int) -> int:
        w = max(self.n_walkers or 96, 2 * q)  # emcee's moves want at least 2·q walkers
        return w + (w % 2)


@dataclass
class Check:
    """One stopping check: at ``steps``, burn-in ``burn``; the worst R-hat and ESS / target over the gating quantities."""

    steps: int
    burn: int
    max_rhat: float
    min_ess_ratio: float


@dataclass
class SamplingResult:
    """Chains of every ensemble after burn-in, in internal units.

    ``chains``: (K, steps, walkers, q); ``log_prob``: (K, steps, walkers);
    ``tau``: (K, q) in steps, of the deviations and sigma_model (NaN for the nuisance terms, whose τ
    nothing reads); ``n_steps``: total steps per ensemble; ``burn``.
    """

    posterior: LogPosterior
    chains: np.ndarray
    log_prob: np.ndarray
    tau: np.ndarray
    n_steps: int
    burn: int
    converged: bool
    acceptance: np.ndarray  # (K,)
    wall_time: float
    settings: SamplerSettings
    approximation: PosteriorApproximation | None = None
    independence_acceptance: float = float("nan")
    checks: list[Check] = field(default_factory=list)
    messages: list[str] = field(default_factory=list)

    @property
    def n_draws(self) -> int:
        """Kept draws over all ensembles (steps × walkers × ensembles)."""
        return int(np.prod(self.chains.shape[:3]))


class _GrowingBackend(emcee.backends.Backend):
    """emcee's in-memory backend, preallocating geometrically: a run of n steps copies its chain O(log n) times."""

    def grow(self, ngrow, blobs):
        free = len(self.chain) - self.iteration
        if ngrow > free:
            super().grow(max(ngrow, 2 * len(self.chain) - self.iteration), blobs)


def _gating(post: LogPosterior) -> list[str]:
    """The quantities whose convergence stops a run: every quantity the posterior reports (:func:`.analytic.reported`,
    whatever the data determine of it: a prior-dominated one must mix too), then the sampled discrepancy scales."""
    return list(reported(post)) + list(post.sampled_scales)


def _gating_draws(post: LogPosterior, chains_z: np.ndarray) -> dict[str, np.ndarray]:
    """Display-unit draws ``(K, S, W)`` of the gating quantities from sampling coordinates ``(K, S, W, q)``."""
    d = display_draws(post.names, post.to_theta(chains_z))
    return {n: d[n] for n in _gating(post) if n in d}


def _walker_major(x: np.ndarray) -> np.ndarray:
    """``(K, S, W)`` -> ``(K, W·S)``: each chain the walkers' sequences one after the other (ArviZ sees each
    walker's own autocorrelation)."""
    return np.swapaxes(x, 1, 2).reshape(x.shape[0], -1)


def _split_rhat(draws: dict[str, np.ndarray]) -> float:
    """Largest rank-normalised R-hat over 2K chains: every ensemble's first and second half in time."""
    worst = 0.0
    for x in draws.values():
        half = x.shape[1] // 2
        split = np.concatenate([_walker_major(x[:, :half]), _walker_major(x[:, half:2 * half])])
        worst = max(worst, float(az.rhat(split, method="rank")))
    return worst


def _ess_ratio(draws: dict[str, np.ndarray], s: SamplerSettings) -> float:
    """Smallest bulk or tail ESS over its target, over the gating quantities."""
    worst = math.inf
    for name, x in draws.items():
        target = s.target_ess_sigma if is_scale(name) else s.target_ess
        flat = _walker_major(x)
        ess = min(float(az.ess(flat, method="bulk")), float(az.ess(flat, method="tail")))
        worst = min(worst, ess / target)
    return worst


def _tau(x: np.ndarray) -> float:
    """Integrated autocorrelation time, steps, of draws ``(K, S, W)``: ``K·S·W / ESS`` with ArviZ's ESS of the mean
    (each walker's own autocorrelation, all ensembles at once)."""
    return float(x.size / az.ess(_walker_major(x), method="mean"))


def _tau_of_quantities(post: LogPosterior, chains_z: np.ndarray) -> np.ndarray:
    """τ (K, q) of the deviations and sigma_model, one value for all ensembles (K, S, W, q); NaN for the nuisance
    terms, whose τ nothing reads."""
    cols = [i for i, p in enumerate(post.space.parameters) if p.group == "deviation"] + list(range(post.p, len(post)))
    tau = np.full(chains_z.shape[::3], np.nan)
    for i in cols:
        tau[:, i] = _tau(chains_z[..., i])
    return tau


def _check(post: LogPosterior, chains_z: np.ndarray, s: SamplerSettings) -> Check:
    """Detect the burn-in and measure R-hat and ESS of the kept part of ``chains_z`` (K, S, W, q)."""
    S = chains_z.shape[1]
    gate = _gating_draws(post, chains_z)
    tau = max(_tau(x) for x in gate.values())
    burn = rhat = None
    for b in (max(2, math.ceil(2 * tau)), S // 4, S // 2):
        if b >= S - 4:
            continue
        rhat = _split_rhat({n: x[:, b:] for n, x in gate.items()})
        burn = b
        if rhat <= s.max_rhat:
            break
    if burn is None:
        return Check(S, S // 2, math.inf, 0.0)
    return Check(S, burn, rhat, _ess_ratio({n: x[:, burn:] for n, x in gate.items()}, s))


def _next_length(c: Check, s: SamplerSettings) -> int:
    """Where the next check goes: the length the ESS rate predicts (+25 %), at least 10 steps on, at most double."""
    kept = c.steps - c.burn
    wanted = c.burn + kept * 1.25 / max(c.min_ess_ratio, 0.05) if c.max_rhat <= s.max_rhat else 2 * c.steps
    return int(min(s.max_steps, max(c.steps + 10, min(2 * c.steps, math.ceil(wanted)))))


def _backend(checkpoint: Path | None, k: int):
    if checkpoint is None:
        return _GrowingBackend()
    return emcee.backends.HDFBackend(str(checkpoint), name=f"ensemble_{k}")  # whose it is: checkpoint.claim


def _starts(post: LogPosterior, approx: PosteriorApproximation, n: int, random) -> np.ndarray:
    """``n`` starting points ``(n, q)`` drawn from the approximation, all of finite posterior density."""
    out = np.empty((0, len(post)))
    for _ in range(100):
        z = approx.draw_z(n, random)
        out = np.vstack([out, z[np.isfinite(post(z))]])
        if len(out) >= n:
            return out[:n]
    raise MtmcalError("could not find starting points of finite posterior density (check [priors])")


def run_ensembles(post: LogPosterior, settings: SamplerSettings | None = None, checkpoint: str | Path | None = None,
                  progress: Progress | None = None, *,
                  approximation: PosteriorApproximation | None = None) -> SamplingResult:
    """Sample ``post`` with independent emcee ensembles until the targets hold (see the module docstring).

    ``progress`` receives a :class:`~mtmcal_bayes.progress.ProgressEvent` after every stretch of steps
    (task ``"sampling [<model>]"``, steps done and the budget).
    ``checkpoint``: HDF5 file; an existing one with the same run is resumed.  ``approximation``: the
    :class:`PosteriorApproximation` of ``post`` when it is at hand (else it is built).
    """
    s = settings or SamplerSettings()
    if s.sampler == "exact":
        return run_exact(post, s, approximation=approximation)
    t0 = time.perf_counter()
    q, W = len(post), s.walkers(len(post))
    approx = approximation or PosteriorApproximation(post)
    ckpt = Path(checkpoint) if checkpoint else None
    if ckpt is not None:
        claim(ckpt, post, s, W)  # the checkpoint is this run's, or the run stops here
    seeds = np.random.SeedSequence(s.seed).spawn(s.n_ensembles)
    samplers, starts, moves = [], [], []
    for k in range(s.n_ensembles):
        rng = np.random.default_rng(seeds[k])
        backend = _backend(ckpt, k)
        k_moves = s.moves(approx)
        sampler = emcee.EnsembleSampler(W, q, post, vectorize=True, backend=backend, moves=k_moves)
        if sampler.iteration == 0:
            random = np.random.RandomState(rng.integers(2**32 - 1))
            starts.append(_starts(post, approx, W, random))
            sampler.random_state = random.get_state()
        else:
            starts.append(None)
        samplers.append(sampler)
        moves.append(k_moves[0][0])

    # replay the checks a resumed run already passed: every decision depends only on the stored chain
    done = min(sm.iteration for sm in samplers)
    target, checks = s.min_steps, []
    while True:
        for k, sm in enumerate(samplers):
            todo = target - sm.iteration
            if todo > 0:
                sm.run_mcmc(starts[k] if sm.iteration == 0 else None, todo, progress=False)
        c = _check(post, np.stack([sm.get_chain()[:target] for sm in samplers]), s)
        checks.append(c)
        if target > done:
            elapsed = time.perf_counter() - t0
            emit(progress, ProgressEvent(f"sampling [{post.model_name}]", f"step {target} (budget {s.max_steps}), "
                                         f"R-hat {c.max_rhat:.3f}, ESS {c.min_ess_ratio:.2f} × target, "
                                         f"{elapsed:.0f} s", target, s.max_steps, elapsed))
        converged = c.max_rhat <= s.max_rhat and c.min_ess_ratio >= 1.0
        if converged or target >= s.max_steps:
            break
        target = _next_length(c, s)

    burn = c.burn
    chains_z = np.stack([sm.get_chain(discard=burn)[: target - burn] for sm in samplers])
    log_prob = np.stack([sm.get_log_prob(discard=burn)[: target - burn] for sm in samplers])
    tau = _tau_of_quantities(post, chains_z)
    messages = []
    if not converged:
        messages.append(f"step budget of {s.max_steps} reached before the targets: kept {target - burn} steps, "
                        f"R-hat {c.max_rhat:.3f} (want ≤ {s.max_rhat}), smallest ESS {c.min_ess_ratio:.2f} × its "
                        f"target (want ≥ 1)")
    proposed = sum(m.proposed for m in moves)
    return SamplingResult(
        posterior=post, chains=post.to_theta(chains_z), log_prob=log_prob, tau=tau, n_steps=target, burn=burn,
        converged=converged, acceptance=np.array([np.mean(sm.acceptance_fraction) for sm in samplers]),
        wall_time=time.perf_counter() - t0, settings=s, approximation=approx,
        independence_acceptance=sum(m.accepted for m in moves) / proposed if proposed else float("nan"),
        checks=checks, messages=messages)


def run_exact(post: LogPosterior, settings: SamplerSettings, *,
              approximation: PosteriorApproximation | None = None) -> SamplingResult:
    """Independent draws of the exact posterior (linear model, normal priors), shaped like a sampler run:
    ``n_ensembles`` chains of ``min_steps × walkers`` draws each, one walker."""
    t0 = time.perf_counter()
    approx = approximation or PosteriorApproximation(post)
    if not approx.exact:
        raise ParameterError("sampler", f"exact: the exact posterior is known for the linear model with normal "
                             f"priors only, not for {post.model_name} here (use the emcee sampler)")
    s = settings
    per_chain = s.min_steps * s.walkers(len(post))
    random = np.random.RandomState(np.random.default_rng(s.seed).integers(2**32 - 1))
    z = approx.draw_z(s.n_ensembles * per_chain, random).reshape(s.n_ensembles, per_chain, 1, len(post))
    log_prob = np.stack([post(zk[:, 0]) for zk in z])[..., None]
    return SamplingResult(
        posterior=post, chains=post.to_theta(z), log_prob=log_prob, tau=np.ones((s.n_ensembles, len(post))),
        n_steps=per_chain, burn=0, converged=True, acceptance=np.ones(s.n_ensembles),
        wall_time=time.perf_counter() - t0, settings=s, approximation=approx, independence_acceptance=1.0)
