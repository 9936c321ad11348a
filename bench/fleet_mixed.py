"""A fleet of mixed machine types on 2 Dask workers against 1: speed-up and identical seeded results.

    python bench/fleet_mixed.py [--machines 7] [--campaigns 4] [--sampler exact] [--keep DIR]

The fleet: ``--machines`` machines of each of four types — the thesis machine (simulated from the thesis campaign,
deviations zero) and the three described built-in types (vertical-turn-mill, trunnion, head-head: simulated from
their demo campaigns' ``[truth]`` with the chain model) — each with ``--campaigns`` quarterly campaigns (a
simulated history, fresh set-up offsets and noise; every third machine with a 40″ step in one of its own
deviations from the third campaign on), each type with its ``[machine] type`` so σ_model is pooled per type.
Default 4 × 7 × 4 = 112 campaign posteriors and 28 histories.

``mb.fleet`` runs it on a fresh local cluster of 1 and of 2 workers, without a cache, each run timed whole (cluster
start, the workers' imports, every posterior, every history, the pooling).  The results (``machines`` and
``errors``) of both runs must be identical.  Prints one Markdown table and a JSON line (docs/fleet.md quotes them).
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import mtmcal_bayes as mb
from mtmcal_bayes import api
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.io.json_text import json_text

#: the four types and the deviation a stepped machine of the type changes
TYPES = {"integrex-i200": "beta_XB", "vertical-turn-mill": "E_A0B", "trunnion": "E_B0C", "head-head": "E_B0A"}


def build_tree(root: Path, machines: int, campaigns: int) -> int:
    """The mixed fleet below ``root``; returns the number of campaigns written."""
    n = 0
    for t, (kind, stepped) in enumerate(TYPES.items()):
        base = api.demo_campaign(kind)
        truth = Truth({}) if base is None else None
        for i in range(machines):
            serial = f"{kind[:4].upper()}-{i + 1:03d}"
            steps = [f"{stepped}=40@3"] if i % 3 == 2 and campaigns >= 3 else []
            api.simulate_history(base, truth=truth, n=campaigns, steps=steps, serial=serial, seed=1000 * t + i,
                                 output=root / serial, machine_type=kind.upper())
            n += campaigns
    return n


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--machines", type=int, default=7, help="machines per type")
    ap.add_argument("--campaigns", type=int, default=4, help="campaigns per machine")
    ap.add_argument("--sampler", default="exact", help="the campaigns' sampler (exact: independent draws, linear)")
    ap.add_argument("--keep", default=None, help="build the fleet in this folder (kept) instead of a temporary one")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="mtmcal-fleet-mixed-") as tmp:
        root = Path(args.keep or tmp) / "plant"
        n = build_tree(root, args.machines, args.campaigns)
        times, results, units = {}, {}, {}
        for w in (1, 2):
            t0 = time.perf_counter()
            r = mb.fleet(root, workers=w, cache=False, sampler=args.sampler)
            times[w] = time.perf_counter() - t0
            results[w] = json_text(r.results_json())
            units[w] = (r.run["units"], r.run["failed"], r.run["compute_time_s"])
        same = results[1] == results[2]
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"{n} campaigns of {4 * args.machines} machines of 4 types ({units[1][0]} units, {units[1][1]} failed), "
          f"sampler {args.sampler}; load average {load:.1f}")
    print("| workers | wall time | campaigns per minute | units' own time |")
    print("|---|---:|---:|---:|")
    for w in (1, 2):
        print(f"| {w} | {times[w]:.1f} s | {60 * n / times[w]:.0f} | {units[w][2]:.1f} s |")
    print(f"speed-up 2 workers / 1: {times[1] / times[2]:.2f}×; identical results: {same}")
    print(json.dumps({"campaigns": n, "wall_s": times, "speed_up": times[1] / times[2], "identical": same}))


if __name__ == "__main__":
    main()
