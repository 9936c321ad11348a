"""Coverage of the identified axis lines (issue 37, item 4): on machines drawn from the priors, how often the 95 %
HDI of each number ``axes`` states as determined covers the true line's.

    python bench/axis_coverage.py [--machines 50] [--type trunnion] [--seed 1]

Each machine: deviations drawn from their priors (the nuisance terms too), the demo campaign's measurements
simulated through the chain with the instruments' scatter (``simulate`` with noise), the exact posterior sampled,
``axis_lines`` computed; the truth's lines through the same chain.  Prints one JSON document: per type the share
of determined numbers covered (goal ≥ 0.90 at a 95 % interval) and the number of machines.
"""

from __future__ import annotations

import argparse
import json

import numpy as np

import mtmcal_bayes as mb
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.io.machine_reader import demo_campaign, description_of
from mtmcal_bayes.machines import generated
from mtmcal_bayes.machines.chain import Chain
from mtmcal_bayes.posterior.axis_lines import _lines, _quantities, axis_lines
from mtmcal_bayes.simulation.simulate import truth_from_vector


def coverage(machine: str, n: int, seed: int) -> dict:
    base = mb.load_campaign(demo_campaign(machine))
    post = LogPosterior(base, "linear", data="both", sigma_model=0.0)
    rng = np.random.default_rng(seed)
    desc = description_of(base.machine)
    chain = Chain(desc, generated(desc))
    covered = total = 0
    for k in range(n):
        theta = np.array([q.frozen().rvs(random_state=rng) for q in post.priors.priors[:post.p]])
        truth = truth_from_vector(post.space, theta)
        sim = mb.simulate(base, truth=truth, model="chain", noise=True, seed=seed * 1000 + k)
        c = sim.synthetic_campaign()
        lines = axis_lines(mb.sample(c, sampler="exact", seed=k))
        true = _quantities(desc, _lines(chain, desc, {n_: np.array([v]) for n_, v in truth.deviations.items()}, 1))
        for _, r in lines.table.iterrows():
            if r["determined"] and r["sd"] > 1e-12:
                t = true[r["element"], r["quantity"]][0][0]
                covered += int(r["hdi_low"] <= t <= r["hdi_high"])
                total += 1
    return {"machines": n, "determined_numbers": total, "covered_share": covered / total, "goal": 0.90}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--machines", type=int, default=50)
    ap.add_argument("--type", action="append", default=None)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    types = args.type or ["vertical-turn-mill", "trunnion", "head-head"]
    print(json.dumps({t: coverage(t, args.machines, args.seed) for t in types}, indent=2))


if __name__ == "__main__":
    main()
