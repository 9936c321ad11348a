"""emcee ensembles until converged: several independent ensembles, adaptive length, checkpoints.

* ``n_ensembles`` (≥ 4) independent :class:`emcee.EnsembleSampler` runs with
  ``vectorize=True`` — the log posterior is evaluated for half an ensemble in
  one call.  The walkers of one ensemble are not independent chains, the
  ensembles are: R-hat is computed across ensembles.
* Moves: differential evolution (80 %) and the stretch move (20 %); in these
  20–30 dimensions this mixes faster than the stretch move alone.  (emcee's
  DESnookerMove is not used: on a 24-dimensional standard normal it returned
  sds of 0.75, i.e. it does not sample the target.)
* Dispersed starts: each ensemble starts from its own draws of the Gaussian
  (linearised) posterior widened threefold, sigma_model from its prior.
* Run length: the ensembles advance together in blocks of ``check_every``
  steps.  After each block the first quarter is discarded as burn-in and the
  integrated autocorrelation time τ of every parameter is estimated with
  :func:`emcee.autocorr.integrated_time` (averaged over walkers).  The run stops
  when the kept length is at least ``min_tau_multiple`` × τ for every
  deviation in every ensemble and τ changed by less than ``tau_tolerance``
  since the previous block — or at ``max_steps``, with a warning.  The
  nuisance parameters and sigma_model do not gate the stop (sigma_model's τ is
  2–3× that of the deviations, its posterior close to its prior); their R-hat
  and ESS are still checked and reported with the others.
* Every decision depends only on the stored chain, and emcee stores its random
  state with every step: a run resumed from its checkpoint continues exactly
  as the uninterrupted run would have.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import emcee
import numpy as np

from ..errors import MtmcalError, ParameterError
from ..progress import Progress, ProgressEvent, emit
from .analytic import gaussian_posterior
from .log_posterior import LogPosterior


@dataclass
class SamplerSettings:
    n_ensembles: int = 4
    n_walkers: int | None = None  # at least 2·q (rounded up to even); default max(48, 2·q)
    check_every: int = 500
    max_steps: int = 20_000
    min_tau_multiple: float = 50.0
    tau_tolerance: float = 0.05
    start_widening: float = 3.0
    seed: int | None = None

    def __post_init__(self):
        if self.n_ensembles < 2:
            raise ParameterError("n_ensembles", "at least two independent ensembles are needed for R-hat "
                                 "(four by default)")
        check_step_budget(self.max_steps, self.check_every)

    def moves(self):
        return [(emcee.moves.DEMove(), 0.8), (emcee.moves.StretchMove(), 0.2)]

    def walkers(self, q: int) -> int:
        w = max(self.n_walkers or 48, 2 * q)  # emcee's moves want at least 2·q walkers
        return w + (w % 2)


@dataclass
class SamplingResult:
    """Chains of every ensemble after burn-in, in internal units.

    ``chains``: (K, steps, walkers, q); ``log_prob``: (K, steps, walkers);
    ``tau``: (K, q) in steps; ``n_steps``: total steps per ensemble; ``burn``.
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
    messages: list[str] = field(default_factory=list)

    @property
    def n_draws(self) -> int:
        """Kept draws over all ensembles (steps × walkers × ensembles)."""
        return int(np.prod(self.chains.shape[:3]))


def _tau(chain: np.ndarray) -> np.ndarray:
    """τ (q,) of a chain (steps, walkers, q), first quarter discarded."""
    n = chain.shape[0]
    return emcee.autocorr.integrated_time(chain[n // 4:], c=5, tol=0, quiet=True)


def _starts(post: LogPosterior, n: int, rng: np.random.Generator, widen: float) -> np.ndarray:
    """``n`` dispersed starting points in scaled coordinates ``(n, q)``, all of finite posterior."""
    sigma0 = post.fixed_sigma if post.fixed_sigma is not None else float(post.priors.priors[-1].frozen().median())
    g = gaussian_posterior(post, sigma_model=sigma0, allow_non_normal=True)
    out = np.empty((0, len(post)))
    for _ in range(100):
        theta = g.mean + widen * (rng.standard_normal((n, post.p)) @ np.linalg.cholesky(g.cov).T)
        if post.fixed_sigma is None:
            theta = np.column_stack([theta, post.priors.priors[-1].frozen().rvs(size=n, random_state=rng)])
        lp = post.log_prob_theta(theta)
        out = np.vstack([out, post.to_z(theta[np.isfinite(lp)])])
        if len(out) >= n:
            return out[:n]
    raise MtmcalError("could not find starting points of finite posterior density (check [priors])")


def _backend(checkpoint: Path | None, k: int, post: LogPosterior, walkers: int):
    if checkpoint is None:
        return None
    backend = emcee.backends.HDFBackend(str(checkpoint), name=f"ensemble_{k}")
    if backend.initialized and backend.shape != (walkers, len(post)):
        raise MtmcalError(f"{checkpoint}: checkpoint holds another run ({backend.shape[1]} parameters, "
                          f"{backend.shape[0]} walkers; this run has {len(post)}, {walkers}); remove it or "
                          "use another file")
    return backend


def check_step_budget(max_steps: int, block: int) -> None:
    """The ensembles run in whole blocks of ``block`` steps: a smaller budget would be overrun silently."""
    if max_steps < block:
        raise ParameterError("max_steps", f"{max_steps} is below one block of {block} steps")


def run_ensembles(post: LogPosterior, settings: SamplerSettings | None = None, checkpoint: str | Path | None = None,
                  progress: Progress | None = None) -> SamplingResult:
    """Sample ``post`` with independent emcee ensembles until converged (see module docstring).

    ``progress`` receives a :class:`~mtmcal_bayes.progress.ProgressEvent` after every block
    (task ``"sampling [<model>]"``, steps done and the budget).
    ``checkpoint``: HDF5 file; an existing one with the same run is resumed.
    """
    s = settings or SamplerSettings()
    q, W = len(post), s.walkers(len(post))
    ckpt = Path(checkpoint) if checkpoint else None
    seeds = np.random.SeedSequence(s.seed).spawn(s.n_ensembles)
    samplers, starts = [], []
    for k in range(s.n_ensembles):
        rng = np.random.default_rng(seeds[k])
        backend = _backend(ckpt, k, post, W)
        sampler = emcee.EnsembleSampler(W, q, post, vectorize=True, backend=backend, moves=s.moves())
        fresh = sampler.iteration == 0
        if fresh:
            sampler.random_state = np.random.RandomState(rng.integers(2**32 - 1)).get_state()
            starts.append(_starts(post, W, rng, s.start_widening))
        else:
            starts.append(None)
        samplers.append(sampler)

    gate = np.array([p.group == "deviation" for p in post.space.parameters] + [False] * (q - post.p))
    t0 = time.perf_counter()
    block = s.check_every
    # a resumed run continues to the next block boundary of the furthest ensemble
    target = max(block, -(-max(sm.iteration for sm in samplers) // block) * block)
    prev_tau = None
    while True:
        for k, sm in enumerate(samplers):
            todo = target - sm.iteration
            if todo > 0:
                sm.run_mcmc(starts[k] if sm.iteration == 0 else None, todo, progress=False)
        chains = [sm.get_chain()[:, :, gate] for sm in samplers]  # τ of the gating parameters only
        t = np.array([_tau(c) for c in chains])
        if prev_tau is None and target > block:  # resumed: τ of the previous block from the stored chain
            prev_tau = np.array([_tau(c[: target - block]) for c in chains])
        kept = target - target // 4
        tp = prev_tau
        long_enough = bool(np.all(kept >= s.min_tau_multiple * t))
        stable = tp is not None and bool(np.all(np.abs(t - tp) <= s.tau_tolerance * t))
        elapsed = time.perf_counter() - t0
        emit(progress, ProgressEvent(f"sampling [{post.model_name}]", f"step {target} (budget {s.max_steps}), "
                                     f"τ_max ≈ {float(t.max()):.0f} steps, {elapsed:.0f} s", target, s.max_steps, elapsed))
        if (long_enough and stable) or target >= s.max_steps:
            break
        prev_tau = t
        target += block

    burn = target // 4
    tau = np.array([_tau(sm.get_chain()) for sm in samplers])
    messages = []
    converged = long_enough and stable
    if not converged:
        messages.append(f"step budget of {s.max_steps} reached before convergence: kept {target - burn} steps, "
                        f"largest τ of a deviation = {tau[:, gate].max():.0f} steps "
                        f"(want ≥ {s.min_tau_multiple:g} τ, τ stable)")
    return SamplingResult(
        posterior=post,
        chains=np.stack([post.to_theta(sm.get_chain(discard=burn)) for sm in samplers]),
        log_prob=np.stack([sm.get_log_prob(discard=burn) for sm in samplers]),
        tau=tau, n_steps=target, burn=burn, converged=converged,
        acceptance=np.array([np.mean(sm.acceptance_fraction) for sm in samplers]),
        wall_time=time.perf_counter() - t0, settings=s, messages=messages,
    )
