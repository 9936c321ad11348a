"""Does a design from nothing keep its promise on a described machine?  (issue 37, validation)

For each described built-in type: the demo campaign's machine with its set-ups and mounts only; ``design`` to
3″ for every determinable angle and 5 µm for every determinable length (relaxed to what the catalogue can reach
where it cannot, and said so), σ_model contraction 0.5.  Then ``N`` machines drawn from the priors (every
deviation and nuisance term from its prior, σ_model from its prior): the designed campaign simulated through the
nonlinear chain with the repeat scatter, the instrument error and σ_model, and its exact posterior
(``sample --sampler exact``); per target, the share of machines whose realised posterior sd meets it, against the
share the design promises (:data:`mtmcal_bayes.planning.design_problem.PROMISE`) and against its own exact check.

Each share is given with its Clopper–Pearson 95 % interval (``scipy.stats.binomtest``): the promise holds where
the interval contains the promised share or lies above it.  The design's check says whether it simulated through
the chain (:mod:`mtmcal_bayes.planning.design_chain`).

Run: ``python bench/design_described.py [N] [TYPE ...]`` (default 50 machines per type, every described type).
"""

from __future__ import annotations

import copy
import sys
import time

import numpy as np
from scipy import stats

from mtmcal_bayes import api, units
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.errors import ParameterError
from mtmcal_bayes.inference.priors import make_prior
from mtmcal_bayes.machines.space import described_space
from mtmcal_bayes.planning.design_make import design_candidates, make_design
from mtmcal_bayes.planning.design_output import designed_campaign
from mtmcal_bayes.planning.design_problem import PROMISE
from mtmcal_bayes.planning.machine_kit import planner_for
from mtmcal_bayes.planning.scale_priors import scale_prior
from mtmcal_bayes.simulation.simulate import synthetic_campaign, truth_from_vector

TYPES = tuple(sys.argv[2:]) or ("vertical-turn-mill", "trunnion", "head-head")


def new_machine(kind: str):
    c = copy.deepcopy(api.campaign_of(api.demo_campaign(kind)))
    c.ballbar.runs, c.probe, c.truth = [], None, None
    return c


def targets_for(c) -> dict[str, float]:
    """3″ / 5 µm for every deviation the catalogue determines one by one."""
    p = planner_for(c, design_candidates(c), None)
    return {q: (3.0 if p.table[q].unit == "arcsec" else 5.0) for q in p.targets}


def design_to(c, targets, **settings):
    """The design (``settings`` to ``make_design``, e.g. ``instruments``), the targets relaxed by 25 % steps where the
    catalogue cannot reach them."""
    relaxed = {}
    for _ in range(12):
        try:
            return make_design(c, targets=targets, contraction=0.5, seed=0, **settings), relaxed
        except ParameterError as err:
            q = next((t for t in targets if str(err).startswith(f"targets: {t} =")), None)
            if q is None:
                raise
            targets = {**targets, q: targets[q] * 1.25}
            relaxed[q] = targets[q]
    raise RuntimeError("no reachable targets")


def draw_truth(c, rng) -> tuple[Truth, float]:
    """A machine from the priors: every deviation and nuisance term of ``c``'s space, and σ_model."""
    space = described_space(c)
    theta = [make_prior(p.name, p.base, p.kind, c.priors).frozen().rvs(random_state=rng) for p in space.parameters]
    sigma = float(scale_prior(c, "sigma_model", None).frozen().rvs(random_state=rng))
    return truth_from_vector(space, np.asarray(theta, float)), sigma


def share_table(d, sds: np.ndarray) -> None:
    """Per target of design ``d``: its goal, the mean realised sd over the machines ``sds`` (n, t), the share met with
    its Clopper–Pearson 95 % interval, whether the promise holds (the interval reaches :data:`PROMISE`, or the
    check's own share where the check finds it short), and the design's own check beside them."""
    n, goal = len(sds), d.goal.targets
    met = sds <= np.where(np.isfinite(goal), goal, np.inf)
    print(f"  {'target':<12} {'goal':>6} {'realised mean sd':>17} {'share met':>10} {'95 % interval':>14} "
          f"{'holds':>6} {'design check':>13} {'check mean sd':>14}")
    check = d.check.share_met(goal)
    for j, q in enumerate(d.targets):
        if np.isfinite(goal[j]):
            u = units.SYMBOL[d.target_units[j]]
            ci = stats.binomtest(int(met[:, j].sum()), n).proportion_ci(0.95, method="exact")
            # a target the check itself finds short of the promise: the realised share held against the check's
            holds = "yes" if ci.high >= min(PROMISE, check[j]) else "NO"
            print(f"  {q:<12} {goal[j]:>5.3g}{u} {sds[:, j].mean():>15.3g}{u} {met[:, j].mean():>10.1%} "
                  f"{ci.low:>6.1%}–{ci.high:<6.1%} {holds:>6} {check[j]:>13.1%} {d.check.sd_mean[j]:>12.3g}{u}",
                  flush=True)


def main(n: int) -> None:
    for kind in TYPES:
        t0 = time.perf_counter()
        c = new_machine(kind)
        targets = targets_for(c)
        d, relaxed = design_to(c, targets)
        print(f"{kind}: designed in {time.perf_counter() - t0:.0f} s", flush=True)
        planned = designed_campaign(d)
        measured = copy.deepcopy(planned)
        rng = np.random.default_rng(1)
        sds = []
        for i in range(n):
            truth, sigma = draw_truth(measured, rng)
            syn = synthetic_campaign(measured, truth, "chain", noise=True, seed=int(rng.integers(2**31)),
                                     sigma_model=sigma)
            r = api.sample(syn, sampler="exact", seed=1)
            s = r.summary["sd"]
            sds.append([float(s[q]) for q in d.targets])
        sds = np.array(sds)
        k = d.check.kinematics
        print(f"\n{kind}: {len(d.runs)} runs, {d.total_minutes:.0f} min, {d.rounds} round(s); {n} machines from the "
              f"priors ({time.perf_counter() - t0:.0f} s)")
        print(f"  design's check through the {k.model}: {k.through} (misfit {k.misfit_um:.3g} µm, threshold "
              f"{k.threshold_um:.3g} µm)")
        if relaxed:
            print("  relaxed (the catalogue cannot reach 3″/5 µm): " +
                  ", ".join(f"{q} → {v:.3g}" for q, v in relaxed.items()))
        share_table(d, sds)
        print(f"  promise: each target met in at least {PROMISE:.0%} of machines")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 50)
