"""The campaign designer (docs/design.md): speed, the thesis set-up, the promise kept, sequential measuring.

    python bench/design.py [--machines 200]

1. ``mtmcal-bayes design`` on the thesis campaign, whole process, against the import floor
   (``python -c "import arviz, emcee, scipy.stats, numpy"``), both timed in this run (best of 3).
2. The search against exhaustive search on 20 random small problems (6 candidates, 0–3 runs each).
3. The thesis set-up: the thesis campaign's own minutes and sds under the time model; designs from nothing
   (the machine's set-ups and mounts only) for the eight at the thesis' own uncertainty level and at half of
   it; a design from the measured thesis campaign to σ_model contraction 0.5.
4. The promise: a design from nothing measured on N machines drawn from the priors (data from ``simulate``
   plus σ_model's discrepancy; exact posterior): share of machines meeting each target.
5. (Sequential measuring, ``next`` after every run, against the fixed design: ``bench/next_sequential.py``.)
6. On one simulated machine: the thesis campaign's runs measured, then the design from them to contraction
   0.5 measured: the eight quantities' posterior mean ± sd before and after, beside the truth.
"""

import argparse
import copy
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import mtmcal_bayes as mb  # noqa: E402
from mtmcal_bayes import units  # noqa: E402
from mtmcal_bayes.campaign import PlannedRun, Probe  # noqa: E402
from mtmcal_bayes.machine_time import TimeModel  # noqa: E402
from mtmcal_bayes.parameters import IDENTIFIABLE, weights  # noqa: E402
from mtmcal_bayes.planning.design import Planner  # noqa: E402
from mtmcal_bayes.planning.design_output import designed_campaign  # noqa: E402
from mtmcal_bayes.planning.design_problem import MAX_INSTANCES  # noqa: E402
from mtmcal_bayes.planning.design_search import Goal, Search, exhaustive  # noqa: E402
from mtmcal_bayes.plugins.thesis.timing import campaign_clock  # noqa: E402
from tests.machines import SimulatedMachine, realised_sd, small_problem  # noqa: E402


def whole_process(cmd: list[str], repeat: int = 3) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        subprocess.run(cmd, check=True, capture_output=True)
        best = min(best, time.perf_counter() - t0)
    return best


def new_machine(thesis):
    c = copy.deepcopy(thesis)
    c.ballbar.runs, c.probe, c.reported, c.truth = [], Probe(), {}, None
    return c


def thesis_minutes(thesis) -> float:
    bb = thesis.ballbar

    class R:
        def __init__(self, r):
            self.pattern, self.setup, self.mount = r.pattern, bb.setups[r.setup], bb.mounts[r.mount]
            self.repeats = len(next(iter(r.repeats.values())))

    clock = campaign_clock(TimeModel(), thesis)
    return clock.schedule([R(r) for r in bb.runs]).total_min


def fmt(v) -> str:
    return " ".join(f"{x:7.3g}" for x in v)


def section_speed():
    floor = whole_process([sys.executable, "-c", "import arviz, emcee, scipy.stats, numpy"])
    exe = str(Path(sys.executable).parent / "mtmcal-bayes")
    t = whole_process([exe, "design"])
    print(f"1. design on the thesis campaign, whole process: {t:.2f} s; import floor {floor:.2f} s; "
          f"ratio {t / floor:.2f}  (target ≤ 5 s: {'met' if t <= 5 else 'MISSED'})")


def section_search(thesis):
    c = new_machine(thesis)
    rng = np.random.default_rng(0)
    ratios, t_search, t_exh = [], 0.0, 0.0
    while len(ratios) < 20:
        made = small_problem(c, rng)
        if made is None:
            continue
        dp, minutes, tg = made
        goal = Goal(tg, 0.5 if len(ratios) % 2 else None)
        t0 = time.perf_counter()
        ex = exhaustive(dp, goal, minutes, max_count=MAX_INSTANCES)
        t_exh += time.perf_counter() - t0
        if not ex.met:
            continue
        t0 = time.perf_counter()
        r = Search(dp, goal, minutes).run(seed=0)
        t_search += time.perf_counter() - t0
        ratios.append(r.minutes / ex.minutes)
    ratios = np.array(ratios)
    print(f"2. search vs exhaustive (4096 designs each), 20 problems: at the optimum {np.sum(ratios < 1 + 1e-9)}/20, "
          f"worst ratio {ratios.max():.3f}; time {t_search:.2f} s vs {t_exh:.2f} s (ratio {t_exh / t_search:.0f}×)")
    from mtmcal_bayes.planning.design_search import improvement

    rng, shares = np.random.default_rng(12), []
    for budget in (60.0, 90.0, 120.0) * 6:
        made = None
        while made is None:
            made = small_problem(c, rng)
        dp, minutes, _ = made
        goal = Goal(np.full(len(dp.planner.targets), np.nan), None, budget)
        now = dp.value_now()
        best = improvement(dp.value(exhaustive(dp, goal, minutes, max_count=2).counts), now)[0]
        shares.append(improvement(dp.value(Search(dp, goal, minutes).run(seed=0).counts), now)[0] / best)
    shares = np.array(shares)
    print(f"   within a budget alone (60/90/120 min, 729 designs each), 18 problems: at the best "
          f"{np.sum(shares > 1 - 1e-3)}/18, the worst at {shares.min():.1%} of the best improvement")


def section_thesis(thesis):
    own = mb.design(thesis).design
    sd_thesis = own.check.sd_now
    names = own.targets
    print(f"3. thesis campaign as measured: {len(thesis.ballbar.runs)} runs, {thesis_minutes(thesis):.0f} min; "
          f"exact ball-bar sds ({', '.join(names)}):\n   {fmt(sd_thesis)}")
    nm = new_machine(thesis)
    for label, scale in (("thesis level", 1.0), ("half of it", 0.5)):
        t0 = time.perf_counter()
        d = mb.design(nm, targets=dict(zip(names, sd_thesis * scale))).design
        print(f"   from nothing, {label}: {len(d.runs)} runs, {d.total_minutes:.0f} min "
              f"({time.perf_counter() - t0:.1f} s): {', '.join(r.label for r in d.runs)}")
        print(f"     sd after (mean):  {fmt(d.check.sd_mean)}\n     sd after (p90):   {fmt(d.check.sd_quantile(0.9))}"
              f"\n     met in:           {fmt(d.check.share_met(np.asarray(sd_thesis * scale)))}; "
              f"contraction {d.check.contraction.mean():.2f}")
    print(f"   from the measured thesis campaign to contraction 0.5: {len(own.runs)} run(s), {own.total_minutes:.0f} "
          f"min: {', '.join(r.label for r in own.runs)}; contraction {own.check.contraction_now:.2f} → "
          f"{own.check.contraction.mean():.2f} (10–90 %: {np.quantile(own.check.contraction, 0.1):.2f}–"
          f"{np.quantile(own.check.contraction, 0.9):.2f})\n     sd now:           {fmt(own.check.sd_now)}\n"
          f"     sd after (mean):  {fmt(own.check.sd_mean)}")


def section_promise(thesis, n: int):
    nm = new_machine(thesis)
    tg = {"alpha_XB": 1.5, "dy_CZ": 8.0, "alpha_CZ": 10.0}
    d = mb.design(nm, targets=tg).design
    dc = designed_campaign(d)
    t0 = time.perf_counter()
    sds = np.array([realised_sd(SimulatedMachine(nm, 1000 + i, model="linear").measure_all(dc), list(tg)) for i in range(n)])
    share = np.mean(sds <= np.array(list(tg.values())), axis=0)
    promised = d.check.share_met(np.array([tg.get(q, np.nan) for q in d.targets]))
    print(f"4. promise: design from nothing for {tg}: {len(d.runs)} runs, {d.total_minutes:.0f} min; on {n} machines "
          f"({time.perf_counter() - t0:.0f} s) each target met in {', '.join(f'{s:.0%}' for s in share)} "
          f"(preposterior {', '.join(f'{promised[d.targets.index(q)]:.0%}' for q in tg)}; promise 90 %)")


def section_intervals(thesis):
    nm = new_machine(thesis)
    machine = SimulatedMachine(nm, 11, model="linear")
    c = copy.deepcopy(nm)
    c.ballbar.planned = [PlannedRun(r.pattern, r.setup, r.mount, len(next(iter(r.repeats.values())))) for r in
                         thesis.ballbar.runs]
    c = machine.measure_all(c)
    d = mb.design(c).design
    after = machine.measure_all(designed_campaign(d))
    names = list(IDENTIFIABLE)
    truth = [sum(w * machine.values[n] for n, w in weights(q).items()) for q in names]

    def moments(camp):
        pl = Planner(camp, [], names)
        from mtmcal_bayes.planning.design_problem import current_posterior

        now = current_posterior(pl)
        m, s = now.target_moments(pl.observations.mean[None], pl.T)
        scale = np.array([units.from_internal(1.0, u) for u in pl.target_units])
        return m[0] * scale, s[0] * scale, pl.target_units

    m0, s0, u = moments(c)
    m1, s1, _ = moments(after)
    print(f"6. one simulated machine (σ_model {units.from_internal(machine.sigma, 'um'):.2f} µm): the thesis runs, then "
          f"the design to contraction 0.5 ({', '.join(r.label for r in d.runs)})")
    print(f"   {'quantity':<18} {'truth':>8} {'thesis runs: mean ± sd':>24} {'+ design: mean ± sd':>22}")
    for i, q in enumerate(names):
        t = units.from_internal(truth[i], u[i])
        print(f"   {q:<18} {t:8.2f} {m0[i]:12.2f} ± {s0[i]:6.2f}    {m1[i]:10.2f} ± {s1[i]:6.2f}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--machines", type=int, default=200)
    args = ap.parse_args()
    thesis = mb.load_campaign()
    section_speed()
    section_search(thesis)
    section_thesis(thesis)
    section_promise(thesis, args.machines)
    section_intervals(thesis)


if __name__ == "__main__":
    main()
