"""ESS per second: the vectorised log posterior against a scalar one (one Python call per walker).

    python bench/sampler_ess.py [--steps 200] [--model linear]

Same posterior, same seed, same ensembles and step budget; the scalar version
wraps the same function so that emcee calls it once per walker
(``vectorize=False``). ESS is ArviZ's bulk ESS, the smallest over the eight
identifiable quantities.
"""

import argparse
import time

import emcee
import numpy as np

from mtmcal_bayes import load_campaign
from mtmcal_bayes.inference import (
    LogPosterior,
    SamplerSettings,
    run_ensembles,
    summarize,
    to_inference_data,
)
from mtmcal_bayes.parameters import IDENTIFIABLE


class ScalarPosterior:
    """The same posterior, evaluated one parameter vector at a time."""

    def __init__(self, post):
        self.post = post

    def __getattr__(self, name):
        return getattr(self.post, name)

    def __len__(self):
        return len(self.post)

    def __call__(self, z):
        if np.ndim(z) == 2:  # the sampler's own starting-point check passes a batch
            return np.array([self(row) for row in z])
        return float(self.post(z[None, :])[0])


def run(post, steps, vectorize, seed):
    original = emcee.EnsembleSampler.__init__

    def init(self, *a, **k):
        k["vectorize"] = vectorize
        original(self, *a, **k)

    emcee.EnsembleSampler.__init__ = init
    try:
        target = post if vectorize else ScalarPosterior(post)
        t0 = time.perf_counter()
        res = run_ensembles(target, SamplerSettings(seed=seed, min_steps=steps, max_steps=steps))
        wall = time.perf_counter() - t0
    finally:
        emcee.EnsembleSampler.__init__ = original
    res.posterior = post
    s = summarize(to_inference_data(res, seed=seed), post)
    return wall, float(s.loc[list(IDENTIFIABLE), "ess_bulk"].min()), res


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--model", default="linear")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    post = LogPosterior(load_campaign(), args.model)
    tv, ev, rv = run(post, args.steps, True, args.seed)
    ts, es, rs = run(post, args.steps, False, args.seed)
    same = np.array_equal(rv.chains, rs.chains)
    print(f"model {args.model}, 4 ensembles, {args.steps} steps each, {rv.chains.shape[2]} walkers")
    print(f"  vectorised: {tv:7.1f} s, min bulk ESS {ev:8.0f}, ESS/s {ev / tv:8.1f}")
    print(f"  scalar    : {ts:7.1f} s, min bulk ESS {es:8.0f}, ESS/s {es / ts:8.1f}")
    print(f"  ESS/s ratio vectorised/scalar: {(ev / tv) / (es / ts):.1f}x   (identical chains: {same})")


if __name__ == "__main__":
    main()
