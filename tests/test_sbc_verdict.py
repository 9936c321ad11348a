"""The SBC verdict's false-alarm rate does not grow with the number of quantities it is over (Bonferroni,
docs/validation.md): runs of a calibrated posterior with 40 quantities, drawn directly from their rank distribution."""

from __future__ import annotations

import numpy as np
from scipy import stats

from mtmcal_bayes.validation.criteria import INTERVALS, P_MIN
from mtmcal_bayes.validation.sbc import SBCResult, SBCSettings

N, L, Q, RUNS = 200, 99, 40, 200


def _calibrated_run(rng, q: int = Q) -> SBCResult:
    """One SBC run of a calibrated normal posterior: each truth's posterior quantile u is uniform, its rank among L
    posterior draws binomial(L, u), the central intervals cover it where |u − 0.5| < prob / 2."""
    u = rng.uniform(size=(N, q))
    z = stats.norm.ppf(u)
    covered = np.stack([np.abs(u - 0.5) < p / 2 for p in INTERVALS], axis=1)
    return SBCResult(SBCSettings(n=N, n_ranked=L, workers=1), "synthetic", tuple(f"q{j}" for j in range(q)),
                     rng.binomial(L, u), z, np.zeros((N, q)), np.ones((N, q)), np.full(q, 2.0), covered,
                     np.ones(N, bool), np.zeros(N), np.zeros(N), np.zeros(N), 0.0,
                     identified=tuple(f"q{j}" for j in range(q)))


def test_a_calibrated_posterior_of_forty_quantities_fails_the_verdict_in_at_most_two_percent_of_runs():
    """200 runs: the verdict fails in no more runs than a 2 × P_MIN rate allows (its 99.9 % binomial quantile); each
    quantity tested alone at P_MIN (the rule before) fails about half the runs, 1 − 0.98^40."""
    rng = np.random.default_rng(7)
    fails = one_by_one = 0
    for _ in range(RUNS):
        r = _calibrated_run(rng)
        s = r.summary()
        fails += not s["ok"].all()  # every quantity is one the verdict is over
        lo, hi = r.coverage_band(0.9, level=0.99)
        one_by_one += not ((s["p_uniform"] > P_MIN) & s["coverage_90"].between(lo, hi)).all()
    assert fails <= stats.binom.ppf(0.999, RUNS, 2 * P_MIN), fails
    assert one_by_one >= stats.binom.ppf(0.001, RUNS, 0.3), one_by_one


def test_the_threshold_and_the_band_follow_the_family():
    """One quantity: p > 0.01 and the 99 % range (84.0–95.0 % for N = 200), as before; forty: p > 0.01 / 40 and the
    central 1 − 0.01 / 40 range, wider; the text states both."""
    rng = np.random.default_rng(1)
    one, forty = _calibrated_run(rng, 1), _calibrated_run(rng)
    assert one.p_threshold == P_MIN and one.verdict_band() == (0.84, 0.95)
    assert forty.p_threshold == P_MIN / 40
    lo, hi = forty.verdict_band()
    assert lo < 0.84 and hi > 0.95
    doc = forty.document()
    assert doc["family"] == 40 and doc["p_min"] == P_MIN / 40 and doc["coverage_90_band"] == [lo, hi]
