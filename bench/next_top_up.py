"""Where the fixed design leaves a target unmet: its minutes, then ``next`` on the same machine until it says stop.

The comparison ``bench/next_sequential.py`` leaves open on the machines where ``next`` stops later than the fixed
design because the fixed design misses a target: what would finishing the job after the fixed design have cost?  For
each machine seed given (``bench/next_sequential.py`` numbers them from 3000), the same machine (the same draws as
that bench's twin) measures the fixed design in full, then ``next`` names runs on it until every target is met
(:func:`tests.machines.measure_sequentially`, the plan measured in full: σ_model's contraction is not asked again).

Run: ``python bench/next_top_up.py TYPE SEED ... [--every]`` (``--every``: the targets of ``next_sequential.py
--every``), e.g. ``python bench/next_top_up.py trunnion 3003 3030 3036 3049 --every``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path


sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import next_sequential as ns  # noqa: E402  (reads --every from the command line)
from mtmcal_bayes.planning.design_output import designed_campaign  # noqa: E402
from tests.machines import SimulatedMachine, measure_sequentially, realised_sd  # noqa: E402


def main(kind: str, seeds) -> None:
    c = ns.new_machine(kind)
    d, tg = ns.design_for(kind, c)
    planned, names = designed_campaign(d), list(tg)
    for seed in seeds:
        t0 = time.perf_counter()
        machine = SimulatedMachine(c, seed)
        trail = []
        m, minutes, step = measure_sequentially(machine, machine.measure_all(planned, d), trail=trail)
        sd = realised_sd(m, names)
        print(f"machine {seed}: the fixed design {d.total_minutes:.1f} min + next after it {minutes:.1f} = "
              f"{d.total_minutes + minutes:.1f} min ({step.status}); its runs: "
              + "; ".join(f"{t[0]} ({t[5]}) {t[1]:.1f} min" for t in trail)
              + "; sds then: " + ", ".join(f"{q} {s:.3g}" for q, s in zip(names, sd))
              + f" ({time.perf_counter() - t0:.0f} s)", flush=True)


if __name__ == "__main__":
    main(ns.ARGS[0], [int(a) for a in ns.ARGS[1:]])
