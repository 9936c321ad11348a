"""Does ``next``, measured run by run, stop no later than the fixed design?  (issue 44, validation)

Per built-in type: the machine with its set-ups and mounts only (the thesis machine: the thesis campaign without its
runs; a described type: its demo campaign without runs, probe or R-test), a design of ball-bar runs
(``--instruments ballbar``: probe and R-test runs are not measured run by run yet) to a few 3″ / 5 µm targets the
catalogue reaches in a short design (:data:`TARGETS`), σ_model contraction 0.5.  Then ``N`` machines drawn from the
priors (:class:`tests.machines.SimulatedMachine`: every deviation and nuisance term, σ_model; each run measured
through the machine's kinematic model — the thesis plug-in's ``htm-thesis``, a described machine's chain — with the
instrument error, the repeat scatter and σ_model's discrepancy).  On each machine ``next`` after every run
(:func:`tests.machines.measure_sequentially`), and the same machine (a twin: the same draws) measuring the fixed
design in full.

Reported per type: the fixed design (runs, minutes, its exact check's share of machines meeting every target); the
share of machines where ``next`` stopped no later than the fixed design (its minutes ≤ the fixed design's) with the
Clopper–Pearson 95 % interval (``scipy.stats.binomtest``); the mean minutes of each; the share meeting every target
(the realised posterior sd) at ``next``'s stop and after the fixed design; the machines where ``next`` designed the
rest again (a run added), dropped a planned run, stopped with planned runs left; the share of the runs ``next``
named whose ``why`` names a target.

Run: ``python bench/next_sequential.py [N] [TYPE ...]`` (default 50 machines, every type of :data:`TARGETS`; the
types one after another).
"""

from __future__ import annotations

import copy
import sys
import time
from pathlib import Path

import numpy as np
from scipy import stats

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import mtmcal_bayes as mb
from mtmcal_bayes import api
from mtmcal_bayes.campaign import Probe
from mtmcal_bayes.planning.design_make import make_design
from mtmcal_bayes.planning.design_output import designed_campaign
from tests.machines import SimulatedMachine, measure_sequentially, realised_sd

#: per type, the targets (″ / µm): a few of the 3″/5 µm ones of bench/design_described.py whose design is short
TARGETS = {
    "thesis": {"alpha_XB": 1.5, "dy_CZ": 8.0},  # the thesis new machine's, as in bench/design.py
    "trunnion": {"E_B0A": 3.0, "E_C0A": 3.0, "E_X0C": 5.0},
    "head-head": {"E_A0C": 3.0, "E_B0C": 3.0, "E_Y0A": 5.0},
    "vertical-turn-mill": {"E_A0B": 1.5, "E_C0B": 1.5},  # the C tilts, the C line or E_B0B at 3″/5 µm: 21–34 runs
    "nutating-head": {"E_A0C": 3.0, "E_B0C": 3.0, "E_X0C": 5.0},
}


def new_machine(kind: str):
    """The machine before any run: its set-ups and mounts only."""
    if kind == "thesis":
        c = copy.deepcopy(mb.load_campaign())
        c.ballbar.runs, c.probe, c.reported, c.truth = [], Probe(), {}, None
        return c
    c = copy.deepcopy(api.campaign_of(api.demo_campaign(kind)))
    c.ballbar.runs, c.probe, c.rtest, c.truth = [], None, None, None
    return c


def cp(k: int, n: int) -> str:
    ci = stats.binomtest(k, n).proportion_ci(0.95, method="exact")
    return f"{k / n:.0%} ({ci.low:.0%}–{ci.high:.0%})"


def one_type(kind: str, n: int) -> dict:
    t0 = time.perf_counter()
    c = new_machine(kind)
    tg = TARGETS[kind]
    d = make_design(c, targets=tg, contraction=0.5, seed=0, instruments=["ballbar"])
    limit = np.array([tg[q] for q in tg])
    fixed = d.total_minutes
    print(f"{kind}: designed in {time.perf_counter() - t0:.0f} s: {len(d.runs)} runs, {fixed:.1f} min, every target "
          f"met on {d.check.share_all_met(d.goal.targets):.0%} of the check's machines", flush=True)
    used, met, fixed_met, runs, added, dropped, early, named, serving = [], [], [], [], [], [], [], 0, 0
    for i in range(n):
        machine = SimulatedMachine(c, 3000 + i)
        twin = copy.deepcopy(machine)  # the same machine measuring the fixed design
        trail = []
        m, minutes, step = measure_sequentially(machine, designed_campaign(d), trail=trail)
        used.append(minutes)
        runs.append(len(trail))
        met.append(bool(step.status == "stop" and np.all(realised_sd(m, list(tg)) <= limit)))
        fixed_met.append(bool(np.all(realised_sd(twin.measure_all(designed_campaign(d)), list(tg)) <= limit)))
        added.append(any(a for *_, a, _ in trail))  # the rest designed again with a run added
        dropped.append(any(x and not a for *_, a, x in trail))  # a kept plan's run dropped
        early.append(bool(step.status == "stop" and step.planned_left))  # stopped with planned runs left
        named += len(trail)
        serving += sum(any(q in why for q in tg) for _, _, why, *_ in trail)
    used, met, fixed_met = np.array(used), np.array(met), np.array(fixed_met)
    no_later = int(np.sum(used <= fixed + 1e-6))
    row = {"type": kind, "targets": ", ".join(f"{q} {v:g}" for q, v in tg.items()), "runs": len(d.runs),
           "fixed": fixed, "check_all": d.check.share_all_met(d.goal.targets), "no_later": cp(no_later, n),
           "next_min": used.mean(), "next_p90": np.quantile(used, 0.9), "next_runs": np.mean(runs),
           "met_next": met.mean(), "met_fixed": fixed_met.mean(), "added": int(np.sum(added)),
           "dropped": int(np.sum(dropped)), "early": int(np.sum(early)), "why": serving / max(named, 1),
           "seconds": time.perf_counter() - t0,
           "later_where_fixed_met": int(np.sum((used > fixed + 1e-6) & fixed_met))}
    print(f"{kind}: {n} machines in {row['seconds']:.0f} s; next no later than the fixed design on {row['no_later']}; "
          f"minutes next {row['next_min']:.1f} (90 %: {row['next_p90']:.1f}) vs fixed {fixed:.1f}, runs "
          f"{row['next_runs']:.1f} vs {len(d.runs)}; every target met at next's stop {row['met_next']:.0%}, after the "
          f"fixed design {row['met_fixed']:.0%}; machines where next designed the rest again {row['added']}, dropped a "
          f"planned run {row['dropped']}, stopped with planned runs left {row['early']}; later where the fixed design "
          f"met the targets: {row['later_where_fixed_met']}; runs whose why names a target {row['why']:.0%}",
          flush=True)
    return row


def main(n: int, kinds) -> None:
    rows = [one_type(k, n) for k in kinds]
    print("\n| type | targets | fixed design: runs, min (check: all met) | next no later (95 % CI) | later where the "
          "fixed design met them | mean min next / fixed | mean runs next | all targets met: next / fixed | "
          "re-designed / dropped / stopped early | why names a target |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['type']} | {r['targets']} | {r['runs']}, {r['fixed']:.1f} ({r['check_all']:.0%}) | "
              f"{r['no_later']} | {r['later_where_fixed_met']} | {r['next_min']:.1f} / {r['fixed']:.1f} | "
              f"{r['next_runs']:.1f} | {r['met_next']:.0%} / {r['met_fixed']:.0%} | {r['added']} / {r['dropped']} / "
              f"{r['early']} | {r['why']:.0%} |")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 50, tuple(sys.argv[2:]) or tuple(TARGETS))
