"""How often the instrument check catches a misread ball bar: its power on a campaign's design (SPEC §17).

Ball-bar offsets written under one reading convention and read under another (:mod:`mtmcal_bayes.conventions`)
reach the model through the matrix ``M_read · M_written⁻¹`` on each run's two components.  Whether the touch
probe then contradicts them depends on the design and on the deviations: :func:`misreading_power` simulates
``n`` campaigns from the fused prior (deviations optionally scaled to a machine's size), both instruments from
one truth, reads the ball bar wrongly, and counts the campaigns on which :func:`~.consistency.predictive_check`
finds a disagreeing group (p < 0.01) in either direction.  With the right reading the same count is the false
alarm rate of the check (eight groups, each at 1 %).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..conventions import run_matrix
from ..inference.log_posterior import LogPosterior
from ..inference.marginal import MarginalPosterior
from .consistency import predictive_check

#: exact posterior draws per replicate and direction
DRAWS = 2000


def with_reading(campaign, reading):
    """A copy of ``campaign`` whose ball-bar runs carry ``reading``: one convention for every run, or
    ``{pattern: convention}`` (runs of other patterns keep theirs)."""
    out = copy.deepcopy(campaign)
    for run in out.ballbar.runs:
        if isinstance(reading, str):
            run.convention = reading
        elif run.pattern in reading:
            run.convention = reading[run.pattern]
    return out


def reread(values: np.ndarray, written, read, post: LogPosterior) -> np.ndarray:
    """Ball-bar means ``(n, m_bb)`` (machine frame as written) as a campaign read with ``read`` sees them."""
    out = values.copy()
    keys = post.forward.observations.keys  # a ball-bar-only posterior: its observations are the ball bar's
    for i, run in enumerate(written.ballbar.runs):
        idx = [j for j, k in enumerate(keys) if k.run == i]
        if len(idx) != 2:
            continue
        T = run_matrix(read.ballbar.runs[i], read.ballbar) @ np.linalg.inv(run_matrix(run, written.ballbar))
        out[:, idx] = values[:, idx] @ T.T
    return out


@dataclass
class Power:
    """``flagged`` of ``n`` simulated campaigns flagged by the check; ``interval`` its 95 % Clopper–Pearson
    interval; ``by_group``: the share flagged per reading group."""

    written: object
    read: object
    n: int
    flagged: int
    interval: tuple[float, float]
    by_group: dict[str, float]

    @property
    def rate(self) -> float:
        return self.flagged / self.n


def _marginal(post: LogPosterior) -> MarginalPosterior:
    priors = post.priors.priors
    return MarginalPosterior(post.forward.design, post.likelihood.base_var, np.array([q.sd for q in priors[: post.p]]) ** 2,
                             [q.frozen() for q in priors[post.p:]], prior_mean=np.array([q.loc for q in priors[: post.p]]),
                             groups=post.scale_of,
                             sigma_max=[5.0 * float(q.frozen().ppf(0.99999)) for q in priors[post.p:]])


def misreading_power(campaign, *, written, read, n: int = 200, seed: int = 0,
                     deviation_scale: float = 1.0) -> Power:
    """The share of ``n`` campaigns simulated from the fused prior (the deviations' draws times
    ``deviation_scale``), ball bar written with ``written`` and read with ``read``, that the check flags."""
    w, r = with_reading(campaign, written), with_reading(campaign, read)
    fused = LogPosterior(w, "linear", data="both")
    bb, pr = LogPosterior(r, "linear", data="ballbar"), LogPosterior(w, "linear", data="probe")
    rng = np.random.default_rng(seed)
    theta = fused.priors.rvs(n, rng)
    dev = [i for i, p in enumerate(fused.space.parameters) if p.group == "deviation"]
    theta[:, dev] *= deviation_scale
    y = fused.likelihood.replicate(fused.forward.predict(theta[:, : fused.p]), fused.sigma(theta), rng)
    m_bb = len(bb.likelihood.y)
    y_bb = reread(y[:, :m_bb], w, r, bb)
    mb, mp = _marginal(bb), _marginal(pr)
    flagged, by_group = 0, {}
    for i in range(n):
        b, p = bb.with_means(y_bb[i]), pr.with_means(y[i, m_bb:])
        tb, sb = mb.draw(y_bb[i], DRAWS, rng)
        tp, sp = mp.draw(y[i, m_bb:], DRAWS, rng)
        g1 = predictive_check(b, p, draws=np.column_stack([tb, sb]))[1]
        g2 = predictive_check(p, b, draws=np.column_stack([tp, sp]))[1]
        groups = np.concatenate([g1["verdict"].to_numpy(), g2["verdict"].to_numpy()]) == "disagree"
        names = list(g1["group"]) + list(g2["group"])
        flagged += int(groups.any())
        for name, hit in zip(names, groups):
            by_group[name] = by_group.get(name, 0) + int(hit)
    lo = stats.beta.ppf(0.025, flagged, n - flagged + 1) if flagged else 0.0
    hi = stats.beta.ppf(0.975, flagged + 1, n - flagged) if flagged < n else 1.0
    return Power(written, read, n, flagged, (float(lo), float(hi)), {k: v / n for k, v in by_group.items()})
