"""Closed-form ranking of the candidate catalogue: batched against one candidate at a time.

    python bench/plan_ranking.py

Batched: one Planner over all candidates (each new run's rows from a campaign of
that run after its mount's first run, one stacked matrix inverse), which is what
``mtmcal-bayes plan`` does.  One at a time: a Planner per candidate (its own
campaign's rows and inverse), as a per-candidate loop would do.  Same numbers; the ratio is measured in this run.  Also the time of
the whole ``plan`` (catalogue, ranking, 51-point sweep, Monte-Carlo check).
"""

import time

import numpy as np

from mtmcal_bayes import load_campaign
from mtmcal_bayes.planning.catalogue import catalogue
from mtmcal_bayes.planning.design import Planner
from mtmcal_bayes.planning.plan import plan


def main():
    campaign = load_campaign()
    cands = catalogue(campaign)
    t0 = time.perf_counter()
    batched = Planner(campaign, cands).evaluate()
    t_batched = time.perf_counter() - t0
    t0 = time.perf_counter()
    single = [Planner(campaign, [c]).evaluate() for c in cands]
    t_single = time.perf_counter() - t0
    same = max(float(np.max(np.abs(s.sd_after[0] - batched.sd_after[k]))) for k, s in enumerate(single))
    t0 = time.perf_counter()
    plan(campaign)
    t_plan = time.perf_counter() - t0
    print(f"{len(cands)} candidates, 8 targets, thesis campaign")
    print(f"  batched        {t_batched:7.3f} s")
    print(f"  one at a time  {t_single:7.3f} s   ratio {t_single / t_batched:.1f}x  (largest sd difference {same:.1e})")
    print(f"  whole plan (ranking + sweep of 51 lengths + Monte-Carlo check of 3): {t_plan:.2f} s")


if __name__ == "__main__":
    main()
