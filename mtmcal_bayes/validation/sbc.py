"""Simulation-based calibration (Talts et al. 2018, arXiv:1804.06788) of the posterior.

For each of ``n`` replicates: draw a truth θ̃ (deviations, mounting offsets,
tool-length errors and sigma_model) from the prior; simulate the campaign's
repeat means from the likelihood, ``ỹ ~ N(f(θ̃), s²/n + u_inst² + σ̃²)``, with
the campaign's own repeat counts, repeat sds and instrument accuracy — exactly
the data-generating process the likelihood assumes; draw from the posterior
given ỹ; rank θ̃ among ``L`` near-independent posterior draws, for every
quantity (:func:`~.criteria.checked_quantities`: on every machine the reported
quantities its campaign's Jacobian determines one by one — on the thesis campaign
the eight of Table 4.5, dx_CZ and dx_BT — and its identifiable combinations Σ w·θ;
then the discrepancy scales).  If the inference is right, each rank is uniform
on {0, …, L} whatever the prior and the design, and the truth lies inside the posterior's
x % highest-density interval in x % of the replicates.

The replicates are independent: they run as Dask tasks
(:func:`~mtmcal_bayes.cluster.dask_client`: a local cluster of ``workers``
processes, or the cluster of a running scheduler), each seeded from its own
child of one :class:`numpy.random.SeedSequence` and stored at its own index,
so the result does not depend on the number of workers or where they run.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np
import pandas as pd
from scipy import stats

from ..arviz_import import az
from ..cluster import dask_client, default_workers, remembered_interrupt
from ..errors import ParameterError, StepFailure
from ..inference.identifiability import Identifiability
from ..inference.log_posterior import LogPosterior
from ..inference.sampling import SamplerSettings
from ..models import check_data, check_model
from ..progress import Progress, ProgressEvent, emit
from .criteria import (  # noqa: F401  (re-exported)
    INTERVALS,
    quantity_level,
    Checked,
    checked_quantities,
    sbc_quantities,
)
from .samplers import make_sampler


@dataclass
class SBCSettings:
    """What to run: ``n`` replicates of ``model`` with ``sampler`` (``"emcee"`` or ``"exact"``).

    ``n_ranked`` = L, the posterior draws each truth is ranked among (ranks 0…L);
    ``max_steps``: the emcee step budget per ensemble; ``workers``: processes of the local Dask cluster;
    ``scheduler``: the address or scheduler file of a running Dask cluster to use instead (``workers`` is then
    the number of its worker threads when the run started, for the record).
    """

    n: int = 200
    model: str = "linear"
    sampler: str = "emcee"
    n_ranked: int = 99
    max_steps: int = SamplerSettings.max_steps
    workers: int = field(default_factory=default_workers)
    seed: int = 1
    data: str = "ballbar"  # the likelihood's measurements: "ballbar", "probe" or "both"
    scheduler: str | None = None

    def check(self) -> None:
        for name, value, low in (("n", self.n, 2), ("workers", self.workers, 1), ("n_ranked", self.n_ranked, 9)):
            if value < low:
                raise ParameterError(name, f"{value} is below {low}")
        check_model(self.model)
        check_data(self.data)


@dataclass
class SBCResult:
    """Ranks and interval hits of every replicate (``N`` replicates, ``Q`` quantities).

    ``ranks`` (N, Q) in 0…L; ``truth``, ``post_mean``, ``post_sd`` (N, Q) display units (″, µm);
    ``covered`` (N, len(INTERVALS), Q) bool; ``converged``, ``n_steps``, ``tau_max``, ``seconds`` (N,).
    """

    settings: SBCSettings
    campaign: str
    quantities: tuple[str, ...]
    ranks: np.ndarray
    truth: np.ndarray
    post_mean: np.ndarray
    post_sd: np.ndarray
    prior_sd: np.ndarray  # (Q,) display units
    covered: np.ndarray
    converged: np.ndarray
    n_steps: np.ndarray
    tau_max: np.ndarray
    seconds: np.ndarray
    wall_time: float
    output: str | None = None  # directory written by :meth:`write`
    files: list[str] = field(default_factory=list)
    #: the quantities the verdict is over (:attr:`Checked.identified`: what the campaign's Jacobian determines)
    identified: tuple[str, ...] = ()
    #: what its campaign determines (undetermined deviations are not ranked)
    identifiability: Identifiability | None = None

    @property
    def n_bins(self) -> int:
        """Histogram bins: a divisor of L + 1, at most 20, with ≥ 5 expected replicates per bin."""
        L1 = self.settings.n_ranked + 1
        for b in range(min(20, L1), 1, -1):
            if L1 % b == 0 and len(self.ranks) / b >= 5:
                return b
        return 2 if L1 % 2 == 0 else 1

    def bin_counts(self) -> np.ndarray:
        """Rank-histogram counts ``(Q, B)``."""
        B, L1 = self.n_bins, self.settings.n_ranked + 1
        return np.stack([np.bincount(self.ranks[:, j] * B // L1, minlength=B) for j in range(len(self.quantities))])

    @property
    def family(self) -> int:
        """How many quantities the verdict is over (the identified ones; every ranked one where none is named)."""
        return len(self.identified) or len(self.quantities)

    @property
    def p_threshold(self) -> float:
        """The uniformity p-value at or below which a quantity fails (:func:`~.criteria.quantity_level`)."""
        return quantity_level(self.family)

    def verdict_band(self) -> tuple[float, float]:
        """The 90 % coverage range a quantity passes in: the central ``1 − p_threshold`` binomial range."""
        return self.coverage_band(0.9, level=1.0 - self.p_threshold)

    def coverage_band(self, prob: float, level: float = 0.99) -> tuple[float, float]:
        """Central ``level`` range of the coverage a calibrated posterior gives over N replicates (binomial)."""
        n = len(self.ranks)
        lo, hi = stats.binom.interval(level, n, prob)
        return lo / n, hi / n

    def summary(self) -> pd.DataFrame:
        """Per quantity: p_uniform (χ² test of the binned ranks), coverage_50/90/95, z-score mean and sd,
        posterior contraction (1 − mean posterior variance / prior variance) and the verdict."""
        counts = self.bin_counts()
        rows = {}
        z = (self.post_mean - self.truth) / self.post_sd
        for j, q in enumerate(self.quantities):
            chi2, p = stats.chisquare(counts[j]) if counts.shape[1] > 1 else (np.nan, np.nan)
            row = {"p_uniform": float(p), "chi2": float(chi2)}
            for k, prob in enumerate(INTERVALS):
                row[f"coverage_{round(100 * prob)}"] = float(self.covered[:, k, j].mean())
            row["z_mean"] = float(z[:, j].mean())
            row["z_sd"] = float(z[:, j].std(ddof=1))
            row["contraction"] = float(1.0 - np.mean(self.post_sd[:, j] ** 2) / self.prior_sd[j] ** 2)
            lo, hi = self.verdict_band()
            row["ok"] = bool(p > self.p_threshold and lo <= row["coverage_90"] <= hi)
            rows[q] = row
        return pd.DataFrame(rows).T.astype({"ok": bool})

    def write(self, out_dir) -> list[str]:
        """Write sbc.json, sbc_summary.csv, sbc_replicates.csv, sbc_ranks.png, sbc_ecdf.png into ``out_dir``."""
        from .output import write_sbc

        self.files = write_sbc(self, out_dir)
        self.output = str(out_dir)
        return self.files

    def to_json(self) -> dict:
        """What ``validate sbc --json`` prints: :meth:`document` and where it was written."""
        return {**self.document(), "output": self.output, "files": self.files}

    def to_text(self) -> str:
        """What ``validate sbc`` prints."""
        from .output import format_sbc

        text = format_sbc(self)
        if self.files:
            text += f"\n\nSBC written to {self.output}/: {', '.join(self.files)}"
        return text

    def document(self) -> dict:
        """p_uniform and coverage_50/90/95 per quantity, the settings and the verdict (sbc.json)."""
        s = self.summary()
        lo, hi = self.verdict_band()
        return {
            "campaign": self.campaign, "model": self.settings.model, "sampler": self.settings.sampler,
            "n": len(self.ranks), "n_ranked": self.settings.n_ranked, "n_bins": self.n_bins,
            "seed": self.settings.seed, "workers": self.settings.workers, "scheduler": self.settings.scheduler,
            "max_steps": self.settings.max_steps if self.settings.sampler == "emcee" else None,
            "wall_time_s": self.wall_time, "replicate_seconds_median": float(np.median(self.seconds)),
            "replicates_not_converged": int((~self.converged).sum()),
            "family": self.family, "p_min": self.p_threshold, "coverage_90_band": [lo, hi],
            "quantities": {q: {k: (bool(v) if k == "ok" else float(v)) for k, v in s.loc[q].items()}
                           for q in self.quantities},
            "all_ok": bool(s.loc[list(self.identified), "ok"].all()),
            **({} if self.identifiability is None else {"identifiability": self.identifiability.as_dict(),
                                                         "not_checked": list(self.identifiability.undetermined)}),
        }

    def replicates(self) -> pd.DataFrame:
        """One row per replicate: truth, rank, posterior mean and sd of every quantity, sampler facts."""
        cols = {"replicate": np.arange(len(self.ranks)), "converged": self.converged, "n_steps": self.n_steps,
                "tau_max": self.tau_max, "seconds": self.seconds}
        for j, q in enumerate(self.quantities):
            cols.update({f"{q} truth": self.truth[:, j], f"{q} rank": self.ranks[:, j],
                         f"{q} mean": self.post_mean[:, j], f"{q} sd": self.post_sd[:, j]})
        return pd.DataFrame(cols)


def quantity_values(post: LogPosterior, theta: np.ndarray, checked: Checked | None = None) -> np.ndarray:
    """The ranked quantities ``(n, Q)`` (display units) of parameter draws ``(n, q)`` (internal units);
    ``checked``: what is ranked (default :func:`checked_quantities` of ``post``)."""
    return (checked or checked_quantities(post)).values(post, theta)


def simulate_data(post: LogPosterior, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """A truth from the prior ``(q,)`` and repeat means simulated from the likelihood ``(m,)``, mm."""
    theta = post.priors.rvs(1, rng)
    pred = post.forward.predict(theta[:, : post.p])
    return theta[0], post.likelihood.replicate(pred, post.sigma(theta), rng)[0]


def one_replicate(post: LogPosterior, sampler, n_ranked: int, seed: np.random.SeedSequence, *,
                  checked: Checked | None = None) -> dict:
    """Simulate, sample and rank one replicate (see module docstring)."""
    checked = checked or checked_quantities(post)
    rng = np.random.default_rng(seed)
    theta, y = simulate_data(post, rng)
    t0 = time.perf_counter()
    draws = sampler(post.with_means(y), n_ranked, rng)
    truth = checked.values(post, theta[None])[0]
    ranked, full = checked.values(post, draws.ranked), checked.values(post, draws.all)
    covered = np.empty((len(INTERVALS), len(truth)), dtype=bool)
    for k, prob in enumerate(INTERVALS):
        for j in range(len(truth)):
            lo, hi = az.hdi(full[:, j], hdi_prob=prob)
            covered[k, j] = lo <= truth[j] <= hi
    return {"rank": (ranked < truth).sum(axis=0), "truth": truth, "mean": full.mean(axis=0),
            "sd": full.std(axis=0, ddof=1), "covered": covered, "converged": draws.converged,
            "n_steps": draws.n_steps, "tau_max": draws.tau_max, "seconds": time.perf_counter() - t0}


class _Replicates:
    """What every task needs, sent once to each worker (``Client.scatter``): the recipe of the posterior, the
    sampler, L and the ranked quantities (computed once, by the caller).  The posterior is built on first use in
    each worker process and never sent."""

    def __init__(self, campaign, s: SBCSettings, sampler, checked: Checked):
        self.campaign, self.sampler, self.checked = campaign, sampler, checked
        self.model, self.data, self.n_ranked = s.model, s.data, s.n_ranked
        self._post: LogPosterior | None = None

    def __getstate__(self) -> dict:
        return {**self.__dict__, "_post": None}

    def __call__(self, seeds: list[np.random.SeedSequence]) -> list[dict]:
        step = f"the posterior of {self.campaign.source} ({self.model}, data {self.data}) on a Dask worker"
        try:
            if self._post is None:
                self._post = LogPosterior(self.campaign, self.model, data=self.data)
            out = []
            for seed in seeds:
                step = f"replicate {seed.spawn_key[-1] + 1} of the simulation-based calibration ({self.model})"
                out.append(one_replicate(self._post, self.sampler, self.n_ranked, seed, checked=self.checked))
        except Exception as exc:  # the package's errors as themselves (e.g. too few draws for L), the rest named
            raise StepFailure.of(step, exc) from None
        return out


def _run_chunk(replicates: _Replicates, seeds: list[np.random.SeedSequence]) -> tuple[list[dict], float]:
    """One Dask task: consecutive replicates, and the seconds they took."""
    t0 = time.perf_counter()
    return replicates(seeds), time.perf_counter() - t0


#: how long a Dask task should take, s.  A task costs the scheduler and the worker a few ms: replicates
#: cheaper than this (the exact sampler's, 10 ms) go in chunks, dearer ones (emcee's, 0.3 s and more) one per task
TASK_S = 0.25
#: how long a run waits for the first worker of a scheduler's cluster, s
WORKER_TIMEOUT_S = 60


def _on_dask(campaign, s: SBCSettings, sampler, seeds: list, *, progress: Progress | None, t0: float,
             checked: Checked) -> tuple[list[dict], int]:
    """Run the replicates of ``seeds`` as Dask tasks; their results in replicate order and the number of workers.

    First one replicate per task, two tasks per worker thread; when the first task returns, its time sizes the
    chunks of the rest (about :data:`TASK_S` each, at least four tasks per thread), all submitted then (the
    scheduler gives them to whichever worker is free, those joining later included).  Results go to their
    replicate's index, so neither the chunks nor the workers change them.  Progress is reported per replicate
    as tasks finish; an interruption (or an error) cancels what is left before the cluster closes."""
    from distributed import as_completed

    n, out = len(seeds), [None] * len(seeds)
    with dask_client(s.scheduler, None if s.scheduler else min(s.workers, n)) as client:
        workers = _wait_for_workers(client, s.scheduler)
        shared = client.scatter(_Replicates(campaign, s, sampler, checked), broadcast=True, hash=False)
        first: dict = {}  # future -> index of its first replicate

        def submit(i: int, size: int):
            f = client.submit(_run_chunk, shared, seeds[i: i + size], pure=False)
            first[f] = i
            return f

        tasks = as_completed([submit(i, 1) for i in range(min(2 * workers, n))])
        queued = min(2 * workers, n)
        try:
            done = 0
            with remembered_interrupt() as interrupt:
                for f in tasks:
                    interrupt.check()
                    results, seconds = f.result()
                    for k, r in enumerate(results, start=first.pop(f)):
                        out[k], done = r, done + 1
                        _replicate_done(progress, s, done, time.perf_counter() - t0)
                    if queued < n:  # the first result: the rest, in chunks sized by its time
                        size = _chunk_size(seconds / len(results), n - queued, workers)
                        for i in range(queued, n, size):
                            tasks.add(submit(i, size))
                        queued = n
                interrupt.check()
        except BaseException:
            client.cancel(list(first), force=True)
            raise
    return out, workers


def _chunk_size(per_replicate: float, left: int, workers: int) -> int:
    """Replicates per task: about :data:`TASK_S` of work, and at least four tasks per worker thread."""
    by_time = int(TASK_S // per_replicate) if per_replicate > 0 else left
    return max(1, min(by_time, left // (4 * workers)))


def _wait_for_workers(client, scheduler: str | None) -> int:
    """The worker threads of the cluster, once there is at least one (a scheduler may have none yet)."""
    try:
        client.wait_for_workers(1, timeout=WORKER_TIMEOUT_S)
    except TimeoutError:
        raise ParameterError("scheduler", f"no Dask worker joined the scheduler {scheduler!r} within "
                             f"{WORKER_TIMEOUT_S} s (start some with: dask worker ADDRESS)") from None
    return sum(client.nthreads().values())


def _replicate_done(progress: Progress | None, s: SBCSettings, done: int, elapsed: float) -> None:
    eta = elapsed / done * (s.n - done)
    emit(progress, ProgressEvent(f"sbc [{s.model}, {s.sampler}]",
                                 f"{done}/{s.n} replicates, {elapsed:.0f} s, about {eta:.0f} s to go", done, s.n, elapsed))


def run_sbc(campaign, settings: SBCSettings | None = None, progress: Progress | None = None,
            sampler=None) -> SBCResult:
    """Simulation-based calibration of ``settings.model`` on the design of ``campaign``.

    ``progress`` receives a :class:`~mtmcal_bayes.progress.ProgressEvent` as replicates finish.  ``sampler``
    replaces the draw strategy named in the settings (any callable
    ``(posterior, L, rng) -> Draws`` with a ``check(posterior)`` method; the
    tests pass deliberately wrong ones to show that SBC catches them).
    """
    s = settings or SBCSettings()
    s.check()
    post = LogPosterior(campaign, s.model, data=s.data)
    sampler = sampler or make_sampler(s.sampler, s.max_steps)
    sampler.check(post)
    checked = checked_quantities(post)
    *seeds, prior_seed = np.random.SeedSequence(s.seed).spawn(s.n + 1)  # one per replicate, one for the prior sd
    t0 = time.perf_counter()
    out, workers = _on_dask(campaign, s, sampler, seeds, progress=progress, t0=t0, checked=checked)
    if s.scheduler:
        s = replace(s, workers=workers)
    stack = lambda key: np.array([r[key] for r in out])
    prior_theta = post.priors.rvs(20_000, np.random.default_rng(prior_seed))
    return SBCResult(
        settings=s, campaign=campaign.source, quantities=checked.names, ranks=stack("rank"), truth=stack("truth"),
        post_mean=stack("mean"), post_sd=stack("sd"), prior_sd=checked.values(post, prior_theta).std(axis=0),
        covered=stack("covered"), converged=stack("converged"), n_steps=stack("n_steps"), tau_max=stack("tau_max"),
        seconds=stack("seconds"), wall_time=time.perf_counter() - t0, identified=checked.identified,
        identifiability=checked.identifiability)
