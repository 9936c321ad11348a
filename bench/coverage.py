"""Coverage of the sampled 95 % HDIs on synthetic campaigns with known truth.

    python bench/coverage.py [--campaigns 10] [--model linear] [--seed 2026]

Truths drawn from the prior; data by `simulate --noise` (htm-thesis kinematics,
repeat scatter and instrument error); posterior sampled with emcee under
``--model``. Counts in how many of the 8 × campaigns cases the 95 % HDI covers
the truth (≥ 72 of 80 wanted: the expected count is 76, sd ≈ 2).
"""

import argparse
import time

import numpy as np

from mtmcal_bayes import IDENTIFIABLE, load_campaign, units
from mtmcal_bayes.inference import (
    LogPosterior,
    SamplerSettings,
    run_ensembles,
    summarize,
    to_inference_data,
)
from mtmcal_bayes.simulation import synthetic_campaign, truth_from_vector


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--campaigns", type=int, default=10)
    ap.add_argument("--model", default="linear")
    ap.add_argument("--seed", type=int, default=2026)
    args = ap.parse_args()
    thesis = load_campaign()
    post0 = LogPosterior(thesis, args.model)
    rng = np.random.default_rng(args.seed)
    covered = total = 0
    for k in range(args.campaigns):
        draw = post0.priors.rvs(1, rng)[0]
        truth = truth_from_vector(post0.space, draw)
        synth = synthetic_campaign(thesis, truth, "htm-thesis", noise=True, seed=int(rng.integers(1 << 31)))
        post = LogPosterior(synth, args.model)
        t0 = time.perf_counter()
        res = run_ensembles(post, SamplerSettings(seed=int(rng.integers(1 << 31))))
        s = summarize(to_inference_data(res), post)
        hits = []
        for name in IDENTIFIABLE:
            true = (truth.deviations["dx_CZ"] - truth.deviations["dx_BT"]) if name == "dx_CZ_minus_dx_BT" \
                else truth.deviations[name]
            true = units.from_internal(true, s.loc[name, "unit"])
            hits.append(s.loc[name, "hdi_low"] <= true <= s.loc[name, "hdi_high"])
        covered += sum(hits)
        total += len(hits)
        print(f"campaign {k + 1}: {sum(hits)}/8 covered, {res.n_steps} steps, max R-hat "
              f"{s['r_hat'].max():.3f}, {time.perf_counter() - t0:.0f} s", flush=True)
    print(f"95 % HDI covers the truth in {covered} of {total} cases")


if __name__ == "__main__":
    main()
