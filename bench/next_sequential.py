"""Does ``next``, measured run by run, stop no later than the fixed design?  (issue 44, validation)

Per built-in type a new machine and a design for it, σ_model contraction 0.5:

* by default **every instrument**: the type's machine with its ball-bar set-ups and mounts, its ``[probe]`` and its
  ``[rtest]`` where its demo (or R-test demo) has them and no run of any instrument
  (``bench/design_every_instrument.py``'s ``new_machine``; the thesis machine: the thesis campaign without its
  ball-bar and probe runs, its styli kept — it has no R-test), designed with every instrument it has a set-up for;
* ``--ballbar``: last round's bench — the machine with its ball-bar set-ups and mounts only (the thesis machine: no
  probe), ``--instruments ballbar``.

Targets: a few 3″ / 5 µm ones the catalogue reaches in a short design (:data:`TARGETS`); ``--every``: 3″ on every
determinable angle and 5 µm on every determinable length (relaxed by 25 % steps where the catalogue cannot reach
them: ``bench/design_described.py``'s ``design_to``).  Then ``N`` machines drawn from the priors
(:class:`tests.machines.SimulatedMachine`: every deviation and nuisance term, every discrepancy scale; each ball-bar,
probe and R-test run measured through the machine's kinematic model — the thesis plug-in's ``htm-thesis``, a
described machine's chain — with the instrument error or repeatability, the repeat scatter and its scale's
discrepancy).  On each machine ``next`` after every run (:func:`tests.machines.measure_sequentially`), and the same
machine (a twin: the same draws) measuring the fixed design in full.

Reported per type: the fixed design (runs per instrument, minutes, its exact check's share of machines meeting every
target); the share of machines where ``next`` stopped no later than the fixed design (its minutes ≤ the fixed
design's) with the Clopper–Pearson 95 % interval (``scipy.stats.binomtest``); the machines where it stopped later,
and among them those where the fixed design met every target; the mean minutes of each; the share meeting every
target (the realised posterior sd of every instrument's data) at ``next``'s stop and after the fixed design, with
the fixed design's share per target; the machines where ``next`` designed the rest again (a run added), dropped a
planned run, stopped with planned runs left; the runs ``next`` named per instrument, the share whose ``why`` names
a target and the share whose ``why`` names σ_model's contraction alone (a run there to teach it).  Each machine
where ``next`` stopped later is listed: its minutes, the fixed design's unmet targets, and run by run what ``next``
measured (its minutes, the runs it added to and dropped from the plan then, its why); the fixed design's runs are
listed once.

``--joint-keep``: the alternative keep rule (docs/design.md, "`next` against the fixed design"): a plan is kept while
its check from today's posterior meets every target *at once* on ``KEEP_SHARE`` of the simulated machines (instead of
each target on its own), to compare.

Run: ``python bench/next_sequential.py [N] [TYPE ...] [--ballbar] [--every] [--joint-keep]`` (default 50 machines,
every type of :data:`TARGETS`, one after another).
"""

from __future__ import annotations

import copy
import sys
import time
from pathlib import Path

import numpy as np
from scipy import stats

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import mtmcal_bayes as mb  # noqa: E402
from mtmcal_bayes import api  # noqa: E402
from mtmcal_bayes.campaign import Probe  # noqa: E402
from mtmcal_bayes.planning import next_plan, next_run  # noqa: E402
from mtmcal_bayes.planning.design_make import make_design, design_candidates  # noqa: E402
from mtmcal_bayes.planning.design_instruments import other_candidates  # noqa: E402
from mtmcal_bayes.planning.design_output import designed_campaign  # noqa: E402
from mtmcal_bayes.planning.machine_kit import planner_for  # noqa: E402
from tests.machines import SimulatedMachine, measure_sequentially, realised_sd  # noqa: E402

FLAGS = {a for a in sys.argv[1:] if a.startswith("--")}
ARGS = [a for a in sys.argv[1:] if not a.startswith("--")]
BALLBAR_ONLY, EVERY, JOINT_KEEP = "--ballbar" in FLAGS, "--every" in FLAGS, "--joint-keep" in FLAGS

#: per type, the targets (″ / µm): a few of the 3″/5 µm ones of bench/design_described.py whose design is short
TARGETS = {
    "thesis": {"alpha_XB": 1.5, "dy_CZ": 8.0},  # the thesis new machine's, as in bench/design.py
    "trunnion": {"E_B0A": 3.0, "E_C0A": 3.0, "E_X0C": 5.0},
    "head-head": {"E_A0C": 3.0, "E_B0C": 3.0, "E_Y0A": 5.0},
    "vertical-turn-mill": {"E_A0B": 1.5, "E_C0B": 1.5},  # the C tilts, the C line or E_B0B at 3″/5 µm: 21–34 runs
    "nutating-head": {"E_A0C": 3.0, "E_B0C": 3.0, "E_X0C": 5.0},
}


def new_machine(kind: str):
    """The machine before any run (module docstring): every instrument's set-up, or (``--ballbar``) the ball bar's."""
    if kind == "thesis":
        c = copy.deepcopy(mb.load_campaign())
        c.ballbar.runs, c.reported, c.truth = [], {}, None
        if BALLBAR_ONLY:
            c.probe = Probe()
        else:
            c.probe.runs = []  # its styli kept: a probe to design with, its sphere at the W-ball mount
        return c
    if not BALLBAR_ONLY:
        from design_every_instrument import new_machine as with_every_instrument

        return with_every_instrument(kind)
    c = copy.deepcopy(api.campaign_of(api.demo_campaign(kind)))
    c.ballbar.runs, c.probe, c.rtest, c.truth = [], None, None, None
    return c


def design_for(kind: str, c):
    """The fixed design and its targets (module docstring)."""
    settings = {"instruments": ["ballbar"]} if BALLBAR_ONLY else {}
    if not EVERY:
        return make_design(c, targets=TARGETS[kind], contraction=0.5, seed=0, **settings), dict(TARGETS[kind])
    from design_described import design_to

    instruments = ["ballbar"] if BALLBAR_ONLY else ["probe", "rtest"]
    p = planner_for(c, design_candidates(c, instruments=settings.get("instruments", ("ballbar",)))
                    + ([] if BALLBAR_ONLY else other_candidates(c, instruments)), None)
    targets = {q: (3.0 if p.table[q].unit == "arcsec" else 5.0) for q in p.targets}
    d, relaxed = design_to(c, targets, **settings)
    return d, {**targets, **relaxed}


def joint_holds(design) -> bool:
    """The alternative keep rule (``--joint-keep``): every target met at once on ``KEEP_SHARE`` of the machines
    simulated from today's posterior (and every targeted quantity determined by the plan)."""
    tg = design.goal.targets
    if design.determined is not None and np.any(np.isfinite(tg) & ~np.asarray(design.determined)):
        return False
    return bool(design.check.share_all_met(tg) >= next_plan.KEEP_SHARE)


def cp(k: int, n: int) -> str:
    ci = stats.binomtest(k, n).proportion_ci(0.95, method="exact")
    return f"{k / n:.0%} ({ci.low:.0%}–{ci.high:.0%})"


def per_instrument(kinds) -> str:
    return ", ".join(f"{kinds.count(i)} {i}" for i in ("ballbar", "probe", "rtest") if kinds.count(i))


def one_type(kind: str, n: int) -> dict:
    t0 = time.perf_counter()
    c = new_machine(kind)
    d, tg = design_for(kind, c)
    names = list(tg)
    limit = np.array([tg[q] for q in names])
    fixed = d.total_minutes
    planned = designed_campaign(d)
    print(f"{kind}: designed in {time.perf_counter() - t0:.0f} s: {len(d.runs)} runs "
          f"({per_instrument([r.instrument for r in d.runs])}), {fixed:.1f} min, every target met on "
          f"{d.check.share_all_met(d.goal.targets):.0%} of the check's machines; targets "
          + ", ".join(f"{q} {v:.3g}" for q, v in tg.items()), flush=True)
    print("  its runs: " + "; ".join(f"{r.label} ({r.instrument}) {m:.1f} min" for r, m in zip(d.runs, d.minutes)),
          flush=True)
    rows = []
    for i in range(n):
        machine = SimulatedMachine(c, 3000 + i)
        twin = copy.deepcopy(machine)  # the same machine measuring the fixed design
        trail = []
        m, minutes, step = measure_sequentially(machine, planned, trail=trail)
        sd_next = realised_sd(m, names)
        sd_fixed = realised_sd(twin.measure_all(planned, d), names)
        rows.append({"minutes": minutes, "runs": len(trail), "met": bool(step.status == "stop"
                                                                         and np.all(sd_next <= limit)),
                     "fixed_each": sd_fixed <= limit, "fixed_sd": sd_fixed,
                     "added": any(t[3] for t in trail),  # the rest designed again with a run added
                     "dropped": any(t[4] and not t[3] for t in trail),  # a kept plan's run dropped
                     "early": bool(step.status == "stop" and step.planned_left),  # stopped with planned runs left
                     "kinds": [t[5] for t in trail], "trail": trail, "serving": sum(any(q in t[2] for q in names) for t in trail),
                     "teaching": sum("teaches σ_model" in t[2] and not any(q in t[2] for q in names)
                                     for t in trail)})
        r = rows[-1]
        print(f"  machine {3000 + i}: next {minutes:.1f} min, {len(trail)} runs, every target met at its stop "
              f"{r['met']}; the fixed design {fixed:.1f} min, every target met {bool(r['fixed_each'].all())} "
              f"({time.perf_counter() - t0:.0f} s)", flush=True)
    used = np.array([r["minutes"] for r in rows])
    fixed_each = np.array([r["fixed_each"] for r in rows])
    fixed_met = fixed_each.all(axis=1)
    later = used > fixed + 1e-6
    kinds = [k for r in rows for k in r["kinds"]]
    row = {"type": kind, "targets": ", ".join(f"{q} {v:.3g}" for q, v in tg.items()), "runs": len(d.runs),
           "design_runs": per_instrument([r.instrument for r in d.runs]),
           "fixed": fixed, "check_all": d.check.share_all_met(d.goal.targets),
           "no_later": cp(int(np.sum(~later)), n), "next_min": used.mean(), "next_p90": np.quantile(used, 0.9),
           "next_runs": np.mean([r["runs"] for r in rows]), "next_kinds": per_instrument(kinds),
           "met_next": np.mean([r["met"] for r in rows]), "met_fixed": fixed_met.mean(),
           "met_fixed_each": dict(zip(names, fixed_each.mean(axis=0))), "met_fixed_ci": cp(int(fixed_met.sum()), n),
           "added": sum(r["added"] for r in rows), "dropped": sum(r["dropped"] for r in rows),
           "early": sum(r["early"] for r in rows),
           "why": sum(r["serving"] for r in rows) / max(len(kinds), 1),
           "why_sigma": sum(r["teaching"] for r in rows) / max(len(kinds), 1), "seconds": time.perf_counter() - t0,
           "later": int(later.sum()), "later_where_fixed_met": int(np.sum(later & fixed_met))}
    print(f"{kind}: {n} machines in {row['seconds']:.0f} s; next no later than the fixed design on {row['no_later']}; "
          f"later on {row['later']}, of which the fixed design met every target on {row['later_where_fixed_met']}; "
          f"minutes next {row['next_min']:.1f} (90 %: {row['next_p90']:.1f}) vs fixed {fixed:.1f}, runs "
          f"{row['next_runs']:.1f} ({row['next_kinds']} in all) vs {len(d.runs)}; every target met at next's stop "
          f"{row['met_next']:.0%}, after the fixed design {row['met_fixed_ci']} (each: "
          + ", ".join(f"{q} {v:.0%}" for q, v in row["met_fixed_each"].items())
          + f"); machines where next designed the rest again {row['added']}, dropped a planned run "
          f"{row['dropped']}, stopped with planned runs left {row['early']}; runs whose why names a target "
          f"{row['why']:.0%}, σ_model's contraction alone {row['why_sigma']:.0%}", flush=True)
    for i in np.flatnonzero(later):
        r = rows[i]
        unmet = [f"{q} {s:.3g} > {v:.3g}" for q, s, v, ok in zip(names, r["fixed_sd"], limit, r["fixed_each"])
                 if not ok]
        print(f"  machine {3000 + i}: next {r['minutes']:.1f} min, {r['runs']} runs ({per_instrument(r['kinds'])}); "
              f"the fixed design {'met every target' if not unmet else 'left unmet ' + ', '.join(unmet)}",
              flush=True)
        for label, minutes, why, added, dropped, instrument in r["trail"]:  # what next did, run by run
            print(f"    {label} ({instrument}) {minutes:.1f} min"
                  + (f"; added {', '.join(added)}" if added else "") + (f"; dropped {', '.join(dropped)}" if dropped
                                                                        else "") + f": {why}", flush=True)
    return row


def main(n: int, kinds) -> None:
    if JOINT_KEEP:
        next_run.plan_holds = joint_holds
    print(f"instruments: {'ball bar' if BALLBAR_ONLY else 'every one the machine has'}; targets: "
          f"{'every determinable deviation' if EVERY else 'a few'}; keep rule: "
          f"{'every target at once' if JOINT_KEEP else 'each target'} on {next_plan.KEEP_SHARE:.0%}", flush=True)
    rows = [one_type(k, n) for k in kinds]
    print("\n| type | targets | fixed design: runs, min (its check: all met) | `next` no later (95 % CI) | later / of "
          "which the fixed design met every target | mean min `next` / fixed | mean runs `next` (instruments) | "
          "every target met at the stop: `next` / fixed | re-designed / dropped / stopped early | why names a target "
          "(σ_model alone) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['type']} | {r['targets']} | {r['runs']} ({r['design_runs']}), {r['fixed']:.1f} "
              f"({r['check_all']:.0%}) | {r['no_later']} | {r['later']} / {r['later_where_fixed_met']} | "
              f"{r['next_min']:.1f} / {r['fixed']:.1f} | {r['next_runs']:.1f} ({r['next_kinds']}) | "
              f"{r['met_next']:.0%} / {r['met_fixed_ci']} | {r['added']} / {r['dropped']} / {r['early']} | "
              f"{r['why']:.0%} ({r['why_sigma']:.0%}) |")


if __name__ == "__main__":
    main(int(next((a for a in ARGS if a.isdigit()), 50)),
         tuple(a for a in ARGS if not a.isdigit()) or (("trunnion", "head-head") if EVERY else tuple(TARGETS)))
