"""Throughput of ``mtmcal-bayes fleet``: campaigns per minute with 1 and 2 workers, and what Dask costs.

    python bench/fleet.py [--machines 4] [--campaigns 3] [--workers 1,2]

A synthetic fleet (``--machines`` machines × ``--campaigns`` dated campaigns each, simulated from the thesis
campaign with ``synthetic_history``) is run by ``mb.fleet`` on a fresh local cluster of 1 and of 2 workers,
without a cache, each run timed whole (cluster start, workers' imports, every campaign's posterior, every
machine's history).  Both give the same results (checked).  Then the overhead of Dask for one campaign: the
fleet of a folder holding one campaign against the same unit of work called in this (warm) process, a plain
loop.  The plain loop over the whole fleet is timed too, as the 1-worker fleet's baseline.

Prints one Markdown table (docs/fleet.md quotes it).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import tempfile
import time
from pathlib import Path

import mtmcal_bayes as mb
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.fleets.discover import discover
from mtmcal_bayes.fleets.units import (
    FleetSettings,
    campaign_unit,
    history_unit,
    unit_seed,
)
from mtmcal_bayes.io.json_text import json_text
from mtmcal_bayes.simulation.history import synthetic_history


def build_tree(root: Path, machines: int, campaigns: int) -> None:
    base = mb.load_campaign()
    dates = [datetime.datetime(2025, 1, 6) + datetime.timedelta(days=91 * k) for k in range(campaigns)]
    for i in range(machines):
        serial = f"BENCH-{i + 1:03d}"
        (root / serial).mkdir(parents=True)
        for c in synthetic_history(base, Truth({}), dates, serial=serial, seed=100 + i):
            mb.save_campaign(c, root / serial / f"{c.date.date()}.toml")


def plain_loop(root: Path, settings: FleetSettings) -> float:
    """Every unit of the fleet, one after the other in this process: no Dask, no cache."""
    t0 = time.perf_counter()
    found = discover(root)
    for m in found.machines:
        for cf in m.campaigns:
            campaign_unit(cf.campaign, settings, unit_seed([cf.digest], settings.seed))
        if len(m.dated) >= 2:
            history_unit([c.campaign for c in m.dated], unit_seed([c.digest for c in m.dated], settings.seed), False)
    return time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--machines", type=int, default=4)
    ap.add_argument("--campaigns", type=int, default=3)
    ap.add_argument("--workers", default="1,2")
    args = ap.parse_args()
    counts = [int(w) for w in args.workers.split(",")]
    settings = FleetSettings()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp) / "fleet"
        build_tree(root, args.machines, args.campaigns)
        n = args.machines * args.campaigns
        one = Path(tmp) / "one"
        one.mkdir()
        first = sorted(root.rglob("*.toml"))[0]
        (one / first.name).write_bytes(first.read_bytes())

        # warm this process (imports, first call) so that the plain loop times the work only
        cf = discover(one).machines[0].campaigns[0]
        campaign_unit(cf.campaign, settings, unit_seed([cf.digest], settings.seed))

        rows, results = [], {}
        t_plain = plain_loop(root, settings)
        rows.append(("plain loop (this process, no Dask)", t_plain, n / t_plain * 60.0))
        for w in counts:
            t0 = time.perf_counter()
            r = mb.fleet(root, workers=w, cache=False)
            t = time.perf_counter() - t0
            results[w] = json_text(r.results_json())
            rows.append((f"fleet, local cluster of {w} worker{'s' * (w > 1)} (units' own time "
                         f"{r.run['compute_time_s']:.1f} s)", t, n / t * 60.0))
        same = len(set(results.values())) == 1

        t0 = time.perf_counter()
        campaign_unit(cf.campaign, settings, unit_seed([cf.digest], settings.seed))
        t_unit = time.perf_counter() - t0
        t0 = time.perf_counter()
        mb.fleet(one, workers=1, cache=False)
        t_one = time.perf_counter() - t0

    print(f"{args.machines} machines × {args.campaigns} campaigns = {n} campaigns and {args.machines} histories; "
          f"{os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at the end; no cache")
    print()
    print("| run | wall time, s | campaigns per minute |")
    print("|---|---:|---:|")
    for name, t, cpm in rows:
        print(f"| {name} | {t:.1f} | {cpm:.1f} |")
    if len(counts) >= 2:
        t1 = rows[1 + counts.index(1)][1] if 1 in counts else rows[1][1]
        t2 = rows[1 + counts.index(max(counts))][1]
        print(f"\nspeed-up {max(counts)} workers / 1 worker: {t1 / t2:.2f}×; identical results: {same}")
    print(f"one campaign: plain call {t_unit:.2f} s, fleet on a local cluster of 1 worker {t_one:.2f} s: "
          f"Dask overhead {t_one - t_unit:.1f} s (cluster start, the worker's imports, scheduling)")
    print(json.dumps({"campaigns": n, "plain_s": t_plain, "fleet_s": {str(w): rows[1 + i][1] for i, w in enumerate(counts)},
                      "one_campaign_plain_s": t_unit, "one_campaign_fleet_s": t_one, "identical": same}))


if __name__ == "__main__":
    main()
