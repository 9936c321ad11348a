"""Search for the design: fewest machine minutes that meet the targets, or most improvement within a budget.

Greedy by criterion gained per machine minute added, then an exchange refinement (drop a run, or swap
one run for another, whenever the targets stay met and the minutes fall; within a budget: whenever the
improvement grows), repeated from :data:`RESTARTS` randomised greedy starts (each score multiplied by
a log-normal factor, the randomised-exchange idea of the optimal-design literature) and the best kept.
Minutes are not additive — set-up changes are shared by the runs at one set-up — so every step asks the
time model for the whole design's schedule; given each candidate's floor (its measuring minutes, which one more run
of it adds at least), the greedy asks it of the candidates in the order of their bound ``gain / floor`` until none
can beat the best rate found (the same pick), and the exchange looks for a swap only where a run could save minutes,
after the drops (a design meeting its targets drops its best run to drop first).  ``tests/test_design.py`` compares the result with
exhaustive search on small candidate sets.

The criterion (:mod:`.design_problem`) is in log units so that sds and the σ_model contraction add up:

* shortfall ``Φ = Σ_t max(0, ln(sd_t / target_t)) + max(0, ln((1 − c)/(1 − C))) + Σ_t ln 2 · (1 + u_t)/2``,
  the last sum over the targets whose sd is met but that the runs leave undetermined, ``sd_t`` the promised sd, ``c`` the contraction, ``C`` its
  target, ``u_t`` the part of the target the runs do not see (:mod:`.determined`: a target the prior alone would
  meet is unmet; the graded part lets a run that sees some of it count before the run that completes it):
  a design meets its targets when ``Φ = 0``;
* improvement ``J = Σ_t ln(sd_t,now / sd_t) + ln((1 − c_now)/(1 − c))`` (sds averaged over σ_model).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .design_problem import MAX_INSTANCES, DesignProblem, DesignValue

#: randomised greedy starts after the plain greedy one
RESTARTS = 3
#: spread of the log-normal factor on the greedy scores of a randomised start
JITTER = 0.3
#: most exchange passes of one start
MAX_PASSES = 30
MET = 1e-9
#: the shortfall of a target the design's runs leave undetermined (its sd met by the prior only): a factor 2 in sd
UNDETERMINED = float(np.log(2.0))
#: designs valued at once by :func:`exhaustive` (memory: 3 × CHUNK × S × P² floats)
CHUNK = 128


@dataclass
class Goal:
    """What a design must reach: ``targets`` (t,) sds in display units (NaN: none), ``contraction`` the σ_model
    contraction (None: none), ``budget`` minutes (None: none)."""

    targets: np.ndarray
    contraction: float | None = None
    budget: float | None = None

    @property
    def has_targets(self) -> bool:
        return bool(np.any(np.isfinite(self.targets))) or self.contraction is not None


def shortfall(v: DesignValue, goal: Goal) -> np.ndarray:
    """(B,) ``Φ`` of designs valued ``v``."""
    has = np.isfinite(goal.targets)
    ratio = np.where(has, v.sd_promised / np.where(has, goal.targets, 1.0), 1.0)
    phi = np.sum(np.maximum(0.0, np.log(ratio)), axis=1)
    if goal.contraction is not None:
        phi = phi + np.maximum(0.0, np.log((1.0 - v.contraction) / (1.0 - goal.contraction)))
    if v.undetermined is not None:  # counted where the sd alone would be met: elsewhere its own shortfall leads
        u = np.where(has & (ratio <= 1.0) & (v.undetermined > 0), 0.5 * (1.0 + v.undetermined), 0.0)
        phi = phi + UNDETERMINED * np.sum(u, axis=1)
    return phi


def improvement(v: DesignValue, now: DesignValue) -> np.ndarray:
    """(B,) ``J`` of designs valued ``v`` against the campaign ``now``."""
    sd = np.sum(np.log(now.sd_mean / np.maximum(v.sd_mean, 1e-300)), axis=1)
    return sd + np.log((1.0 - now.contraction) / np.maximum(1.0 - v.contraction, 1e-300))


@dataclass
class SearchResult:
    counts: np.ndarray  # (K,)
    minutes: float
    value: DesignValue
    met: bool
    starts: int


class Search:
    """The search over count vectors of ``problem``'s candidates with the time model ``minutes(counts)``."""

    def __init__(self, problem: DesignProblem, goal: Goal, minutes: Callable[[np.ndarray], float],
                 allowed: np.ndarray | None = None, *, floor: np.ndarray | None = None):
        self.problem, self.goal, self._minutes = problem, goal, minutes
        #: (K,) the fewest minutes one more run of each candidate adds (its measuring time, set-up changes aside;
        #: None: unknown): a step's rate is at most its gain over it, so the schedule is asked of the candidates
        #: that could still win, best bound first, and a swap only of those that could save minutes
        self.floor = None if floor is None else np.asarray(floor, float)
        self.has_targets = goal.has_targets  # asked at every step: the goal does not change during a search
        #: the contraction a design's shortfall no longer counts (a goal's, met; none: every contraction): the
        #: designs one run larger need not be given theirs (:meth:`.design_problem.DesignProblem.value_plus_one`)
        self._contraction_met = None if not self.has_targets else \
            -np.inf if goal.contraction is None else goal.contraction
        K = len(problem.candidates)
        self.allowed = np.ones(K, dtype=bool) if allowed is None else np.asarray(allowed, dtype=bool)
        self.now = problem.value_now()
        self._cache: dict[bytes, float] = {}

    def minutes(self, counts: np.ndarray) -> float:
        key = counts.astype(np.int8).tobytes()
        if key not in self._cache:
            self._cache[key] = float(self._minutes(counts))
        return self._cache[key]

    def _score(self, v: DesignValue) -> np.ndarray:
        """Lower is better: the shortfall with targets, minus the improvement without."""
        return shortfall(v, self.goal) if self.has_targets else -improvement(v, self.now)

    def _fits(self, m: float) -> bool:
        return self.goal.budget is None or m <= self.goal.budget + 1e-9

    # ------------------------------------------------------------------ greedy
    def greedy(self, rng: np.random.Generator | None = None, start: np.ndarray | None = None) -> np.ndarray:
        K = len(self.problem.candidates)
        counts = np.zeros(K, dtype=int) if start is None else start.copy()
        score = float(self._score(self.problem.value(counts))[0])
        while True:
            if self.has_targets and score <= MET:
                return counts
            vp, ok = self.problem.value_plus_one(counts, contraction_met=self._contraction_met)
            ok &= self.allowed
            scores = self._score(vp)
            gain = score - scores
            m0 = self.minutes(counts)
            if self.floor is not None and self.goal.budget is None:
                pick = self._best_rate(counts, gain, np.flatnonzero(ok & (gain > MET)), m0=m0, rng=rng)
                if pick < 0:
                    return counts
                counts[pick] += 1
                score = float(scores[pick])
                continue
            best, pick = -np.inf, -1
            for k in np.flatnonzero(ok & (gain > MET)):
                trial = counts.copy()
                trial[k] += 1
                m = self.minutes(trial)
                if not self._fits(m):
                    continue
                rate = gain[k] / max(m - m0, 1e-6)
                if rng is not None:
                    rate *= np.exp(JITTER * rng.standard_normal())
                if rate > best:
                    best, pick = rate, k
            if pick < 0:
                return counts
            counts[pick] += 1
            score = float(scores[pick])

    def _best_rate(self, counts, gain, idx, *, m0, rng) -> int:
        """The greedy step's pick among ``idx`` (the same as trying every one in turn, without a budget): the
        schedule asked in the order of each candidate's bound ``gain / floor`` until no bound can beat the best rate
        found; ties to the first candidate, as in turn."""
        jitter = np.exp(JITTER * rng.standard_normal(len(idx))) if rng is not None else np.ones(len(idx))
        bound = gain[idx] * jitter / np.maximum(self.floor[idx], 1e-6)
        best, pick = -np.inf, -1
        for o in np.argsort(-bound, kind="stable"):
            if bound[o] < best:
                break
            k = int(idx[o])
            trial = counts.copy()
            trial[k] += 1
            rate = gain[k] / max(self.minutes(trial) - m0, 1e-6) * jitter[o]
            if rate > best or (rate == best and k < pick):
                best, pick = rate, k
        return pick

    # ------------------------------------------------------------------ exchange
    def _better(self, score: float, m: float, score0: float, m0: float) -> bool:
        if self.has_targets:  # meet the targets, then fewer minutes
            if score0 > MET:
                return score < score0 - MET
            return score <= MET and m < m0 - 1e-9
        return self._fits(m) and (score < score0 - 1e-9 or (abs(score - score0) <= 1e-9 and m < m0 - 1e-9))

    def exchange(self, counts: np.ndarray) -> np.ndarray:
        """Drops and swaps that improve the design, best first, until none does; a design that meets its targets
        drops a run where one can go (the best drop) before any swap is looked for (a swap costs a rank-r update of
        every candidate, a drop one criterion)."""
        counts = counts.copy()
        for _ in range(MAX_PASSES):
            score0 = float(self._score(self.problem.value(counts))[0])
            m0 = self.minutes(counts)
            met = self.has_targets and score0 <= MET
            if met:
                drop = self._best_drop(counts, score0, m0)
                if drop is not None:
                    counts = drop
                    continue
            best = None
            bound = self.floor is not None and self.has_targets and self.goal.budget is None
            for k in np.flatnonzero(counts > 0):
                less = counts.copy()
                less[k] -= 1
                m_less = self.minutes(less)
                if not met:  # a design meeting its targets had its drops weighed above: none helps
                    s_less = float(self._score(self.problem.value(less))[0])
                    if self._better(s_less, m_less, score0, m0):
                        best = self._keep(best, (s_less, m_less, less))
                could = self.allowed.copy()
                if self.floor is not None and met:
                    could &= self.floor < m0 - m_less - 1e-9  # only a swap that could save minutes
                    could[k] = False
                    if not could.any():
                        continue
                vp, ok = self.problem.value_swap(counts, k, contraction_met=self._contraction_met)
                ok &= could
                scores = self._score(vp)
                for j in np.flatnonzero(ok):
                    # with targets a swap must meet them (the design met them) or come nearer (it did not): the
                    # minutes of the others are not needed
                    if self.has_targets and (scores[j] > MET if score0 <= MET else scores[j] >= score0 - MET):
                        continue
                    if bound and best is not None and (scores[j] > best[0] or (
                            scores[j] == best[0] and m_less + self.floor[j] >= best[1] + 1e-9)):
                        continue  # its minutes are at least the floor more than ``less``'s: it cannot beat the best
                    trial = less.copy()
                    trial[j] += 1
                    m = self.minutes(trial)
                    if self._better(float(scores[j]), m, score0, m0):
                        best = self._keep(best, (float(scores[j]), m, trial))
            if not self.has_targets:  # within a budget, room may be left for one more run
                vp, ok = self.problem.value_plus_one(counts)
                scores = self._score(vp)
                for j in np.flatnonzero(ok & self.allowed & (scores < score0 - 1e-9)):
                    trial = counts.copy()
                    trial[j] += 1
                    m = self.minutes(trial)
                    if self._fits(m):
                        best = self._keep(best, (float(scores[j]), m, trial))
            if best is None:
                return counts
            counts = best[2]
        return counts

    def _best_drop(self, counts, score0, m0):
        """The design ``counts`` less the one run whose dropping keeps its targets met and saves most minutes, or
        None where no run can go (every drop weighed at once, :meth:`.DesignProblem.value_minus_one`)."""
        best = None
        v, designs = self.problem.value_minus_one(counts)
        for s_less, less in zip(self._score(v), designs):
            if s_less <= MET:
                m_less = self.minutes(less)
                if self._better(float(s_less), m_less, score0, m0):
                    best = self._keep(best, (float(s_less), m_less, less))
        return None if best is None else best[2]

    @staticmethod
    def _keep(best, new):
        """The better of two ``(score, minutes, counts)``: lower score, then fewer minutes."""
        return new if best is None or (new[0], new[1]) < (best[0], best[1]) else best

    # ------------------------------------------------------------------ run
    def run(self, seed: int | None = 0, restarts: int = RESTARTS, start: np.ndarray | None = None) -> SearchResult:
        """The best of a plain greedy start and ``restarts`` randomised ones, each refined by exchange; ``start``
        (K,) a design to begin every greedy from (a previous round's, its goal since moved), else none."""
        rng = np.random.default_rng(seed)
        best = None
        for r in range(restarts + 1):
            counts = self.exchange(self.greedy(rng if r else None, start=start))
            v = self.problem.value(counts)
            score = float(self._score(v)[0])
            m = self.minutes(counts)
            key = (score if self.has_targets and score > MET else 0.0, m) if self.has_targets else (score, m)
            if best is None or key < best[0]:
                best = (key, counts, v)
        counts, v = best[1], best[2]
        met = bool(shortfall(v, self.goal)[0] <= MET)
        return SearchResult(counts, self.minutes(counts), v, met, restarts + 1)


def exhaustive(problem: DesignProblem, goal: Goal, minutes: Callable[[np.ndarray], float],
               max_count: int = 1) -> SearchResult:
    """The best design by enumerating every count vector with counts up to ``max_count`` (small K only)."""
    K = len(problem.candidates)
    grids = np.stack(np.meshgrid(*[np.arange(max_count + 1)] * K, indexing="ij"), axis=-1).reshape(-1, K)
    s = Search(problem, goal, minutes)
    score = np.concatenate([s._score(problem.value(grids[i:i + CHUNK])) for i in range(0, len(grids), CHUNK)])
    m = np.array([minutes(c) for c in grids])
    if goal.has_targets:
        ok = score <= MET
        if goal.budget is not None:
            ok &= m <= goal.budget + 1e-9
        if not ok.any():
            i = int(np.argmin(score))
        else:
            i = int(np.flatnonzero(ok)[np.argmin(m[ok])])
    else:
        ok = m <= goal.budget + 1e-9
        idx = np.flatnonzero(ok)
        i = int(idx[np.lexsort((m[idx], score[idx]))[0]])
    vi = problem.value(grids[i])
    return SearchResult(grids[i], float(m[i]), vi, bool(shortfall(vi, goal)[0] <= MET), len(grids))


__all__ = ["Goal", "Search", "SearchResult", "shortfall", "improvement", "exhaustive", "MAX_INSTANCES"]
