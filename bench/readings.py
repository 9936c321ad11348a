"""Power of the instrument check against a misread ball bar, on the thesis design (docs/thesis-notes.md).

    python bench/readings.py [--n 200] [--seed 1]

Campaigns simulated from the fused prior of the built-in thesis campaign (ball bar and touch probe from one
truth, both discrepancy scales drawn), the ball bar's offsets written as the built-in campaign reads its B runs
and read back with another reading; the share flagged by the consistency check (a group at p < 0.01 in either
direction), with its 95 % Clopper–Pearson interval.  Deviations at the prior's size (sd 60″, 100 µm) and at a
third of it (a machine within tens of arc seconds).  The first row is the false-alarm rate (the right reading).

Prints one Markdown table.
"""

from __future__ import annotations

import argparse
import time

from mtmcal_bayes.io import load_campaign
from mtmcal_bayes.posterior.misreading import misreading_power

READINGS = ("built-in (the right reading)", "thesis", "B0=+X,B90=+Z", "B0=+Z,B90=+X, BY bar at -Y",
            "B0=+X,B90=-Z, BY bar at -Y")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    c = load_campaign()
    built = {r.pattern: r.convention for r in c.ballbar.runs if r.convention}

    def reading(name):
        if name.startswith("built-in"):
            return built
        if name.endswith("BY bar at -Y"):
            plot = name.split(",")[0] + "," + name.split(",")[1]
            d0, d90 = (p.split("=")[1] for p in plot.split(","))
            flip = lambda d: ("-" if d[0] == "+" else "+") + d[1]  # noqa: E731
            return {"BX": plot, "BY": f"B0={flip(d0)},B90={flip(d90)}"}
        return {"BX": name, "BY": name}

    print("| read as | deviations | flagged | share | 95 % interval | s |\n|---|---|---:|---:|---|---:|")
    for name in READINGS:
        for scale, label in ((1.0, "prior (60″, 100 µm)"), (1 / 3, "a third (20″, 33 µm)")):
            t0 = time.perf_counter()
            p = misreading_power(c, written=built, read=reading(name), n=args.n, seed=args.seed, deviation_scale=scale)
            print(f"| {name} | {label} | {p.flagged}/{p.n} | {p.rate:.2f} | {p.interval[0]:.2f}–{p.interval[1]:.2f} | "
                  f"{time.perf_counter() - t0:.1f} |")


if __name__ == "__main__":
    main()
