"""False alarms and detections of machine histories, measured on simulated histories (docs/history.md).

    python bench/history_alarms.py [--n-null 500] [--n-step 200] [--n-small 200] [--small-step 15]
                                   [--workers 2] [--seed 20260105] [-o bench_history_alarms.json]

Histories of 5 campaigns, 91 days apart from 2026-01-05 (as in tests/test_history.py), simulated from the
thesis campaign with ``synthetic_history`` and fitted with ``fit_history`` (default ``trend="auto"``):

* **null**: nothing changes.  Any flag is a family-wise false alarm; the docs promise ≤ 5 % (``ALPHA``).
* **step**: ``beta_CZ`` steps by 40″ between the 3rd and the 4th campaign.  Detected = (beta_CZ, 4th date)
  flagged; any other flagged (quantity, date) is an extra flag.
* **small step** (``--n-small``, 0 to skip): the same with a ``--small-step`` step (15″ by default).

No scenario has a ramp, so any deviation given a drift rate (``fit.trend["trended"]``) is a spurious trend.

Every history has its own simulation seed and fit seed, drawn from ``numpy.random.SeedSequence(--seed,
spawn_key=(scenario, index))``: history *i* of a scenario is the same whatever the counts and the workers, so
a rerun (or a longer run) gives the same numbers.  The histories run on a local Dask cluster
(``mtmcal_bayes.cluster.dask_client``) of ``--workers`` single-threaded processes.

Rates come with Clopper–Pearson (exact) 95 % intervals.  Prints a Markdown table; writes a JSON with the
numbers and every history's record to ``-o``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):  # one BLAS thread per worker
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import datetime  # noqa: E402
import hashlib  # noqa: E402
import importlib  # noqa: E402
import json  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import time  # noqa: E402
import traceback  # noqa: E402
from collections import Counter  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
from scipy.stats import binomtest  # noqa: E402

REPO = Path(__file__).resolve().parent.parent
DATES = [datetime.datetime(2026, 1, 5) + datetime.timedelta(days=91 * i) for i in range(5)]
STEP_QUANTITY = "beta_CZ"
STEP_AT = 3  # the step happens between DATES[2] and DATES[3]: flagged at DATES[3]
SCENARIOS = {"null": 0, "step": 1, "small": 2}  # the spawn key of each scenario's seeds
PROGRESS_EVERY_S = 30.0
#: the files whose content decides the numbers (hashed into the JSON: others are editing the package)
SOURCES = ["mtmcal_bayes/histories/__init__.py", "mtmcal_bayes/histories/fit.py", "mtmcal_bayes/histories/model.py",
           "mtmcal_bayes/histories/result.py", "mtmcal_bayes/simulation/history.py",
           "mtmcal_bayes/simulation/simulate.py"]


def seeds(root: int, scenario: str, i: int) -> tuple[int, int]:
    """(simulation seed, fit seed) of history ``i`` of ``scenario``."""
    a, b = np.random.SeedSequence(root, spawn_key=(SCENARIOS[scenario], i)).generate_state(2)
    return int(a), int(b)


def one_history(base, scenario: str, i: int, step: float, sim_seed: int, fit_seed: int) -> dict:
    """Simulate and fit one history; its record (runs on a worker)."""
    from mtmcal_bayes.campaign import Truth
    from mtmcal_bayes.histories import fit_history
    from mtmcal_bayes.simulation.history import drift_from_display, synthetic_history

    t0 = time.perf_counter()
    rec = {"scenario": scenario, "index": i, "step": step, "sim_seed": sim_seed, "fit_seed": fit_seed}
    try:
        drifts = [drift_from_display(STEP_QUANTITY, "step", step, DATES[STEP_AT])] if step else []
        camps = synthetic_history(base, Truth(), DATES, drifts=drifts, seed=sim_seed)
        r = fit_history(camps, seed=fit_seed)
    except Exception as exc:  # recorded, counted, not hidden
        rec.update(error=f"{type(exc).__name__}: {exc}", traceback=traceback.format_exc(limit=3),
                   seconds=time.perf_counter() - t0)
        return rec
    target = (STEP_QUANTITY, DATES[STEP_AT])
    flagged = [(c["quantity"], c["date"]) for c in r.flagged]
    others = [c for c in r.changes if (c["quantity"], c["date"]) != target]
    tc = next((c for c in r.changes if (c["quantity"], c["date"]) == target), None)
    trend = dict(r.fit.trend)
    trended = list(trend.pop("trended"))
    rec.update(
        error=None,
        K=len(r.changes),
        level=r.changes[0]["level"],
        flagged=[[q, d.date().isoformat()] for q, d in flagged],
        any_flag=bool(flagged),
        detected=target in flagged,
        extra=[[q, d.date().isoformat()] for q, d in flagged if (q, d) != target],
        target_probability=None if tc is None else tc["probability"],
        target_delta=None if tc is None else tc["delta"],
        max_other_probability=max(c["probability"] for c in others),
        trended=trended,
        log10_bf=trend,
        acceptance=float(r.fit.acceptance),
        tau_max=float(r.fit.tau_max),
        seconds=time.perf_counter() - t0,
    )
    return rec


def rate(k: int, n: int) -> dict:
    if n == 0:
        return {"k": 0, "n": 0, "rate": None, "ci95": [None, None]}
    ci = binomtest(k, n).proportion_ci(confidence_level=0.95, method="exact")
    return {"k": k, "n": n, "rate": k / n, "ci95": [float(ci.low), float(ci.high)]}


def pct(r: dict) -> str:
    if not r["n"]:
        return "–"
    return f"{r['k']}/{r['n']} = {100 * r['rate']:.1f} % [{100 * r['ci95'][0]:.1f}, {100 * r['ci95'][1]:.1f}]"


def summarise(recs: list[dict], scenario: str) -> dict:
    ok = [r for r in recs if r["error"] is None]
    out = {"histories": len(recs), "errors": len(recs) - len(ok),
           "any_flag": rate(sum(r["any_flag"] for r in ok), len(ok)),
           "spurious_trend": rate(sum(bool(r["trended"]) for r in ok), len(ok)),
           "trended_deviations": dict(Counter(q for r in ok for q in r["trended"]).most_common()),
           "flagged_pairs": dict(Counter(f"{q}@{d}" for r in ok for q, d in r["flagged"]).most_common()),
           "pair_flag_rate": rate(sum(len(r["flagged"]) for r in ok), sum(r["K"] for r in ok)),
           "seconds_mean": float(np.mean([r["seconds"] for r in recs])) if recs else None,
           "error_messages": dict(Counter(r["error"] for r in recs if r["error"]).most_common(5))}
    if ok:
        out["level"] = ok[0]["level"]
        out["K"] = ok[0]["K"]
        mo = np.array([r["max_other_probability"] for r in ok])
        out["max_other_probability_quantiles"] = {q: float(np.quantile(mo, q)) for q in (0.5, 0.9, 0.95, 0.99)}
    if scenario != "null":
        out["detected"] = rate(sum(r["detected"] for r in ok), len(ok))
        out["extra_flag"] = rate(sum(bool(r["extra"]) for r in ok), len(ok))
        out["beta_CZ_wrong_date"] = rate(sum(any(q == STEP_QUANTITY for q, _ in r["extra"]) for r in ok), len(ok))
        d = np.array([r["target_delta"] for r in ok])
        p = np.array([r["target_probability"] for r in ok])
        if len(d):
            out["target_delta"] = {"mean": float(d.mean()), "sd": float(d.std(ddof=1)) if len(d) > 1 else None}
            out["target_probability_quantiles"] = {q: float(np.quantile(p, q)) for q in (0.05, 0.1, 0.5)}
    return out


def provenance() -> dict:
    def git(*a):
        try:
            return subprocess.run(["git", *a], cwd=REPO, capture_output=True, text=True, timeout=20).stdout.strip()
        except Exception:
            return None
    hashes = {}
    for s in SOURCES:
        p = REPO / s
        hashes[s] = hashlib.sha256(p.read_bytes()).hexdigest()[:16] if p.exists() else None
    return {"git_head": git("rev-parse", "HEAD"),
            "git_dirty_package_files": git("status", "--porcelain", "--", "mtmcal_bayes").splitlines(),
            "source_sha256_16": hashes}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n-null", type=int, default=500)
    ap.add_argument("--n-step", type=int, default=200)
    ap.add_argument("--n-small", type=int, default=200, help="histories with the smaller step (0: none)")
    ap.add_argument("--step", type=float, default=40.0, help="the step of beta_CZ, arcsec")
    ap.add_argument("--small-step", type=float, default=15.0, help="the smaller step of beta_CZ, arcsec")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--seed", type=int, default=20260105, help="root of every history's SeedSequence")
    ap.add_argument("-o", "--output", default="bench_history_alarms.json")
    args = ap.parse_args()

    import mtmcal_bayes as mb
    from distributed import as_completed

    from mtmcal_bayes.cluster import dask_client

    hfit = importlib.import_module("mtmcal_bayes.histories.fit")  # the package exports fit() under that name
    before = provenance()
    jobs = [(s, i, step) for s, n, step in (("null", args.n_null, 0.0), ("step", args.n_step, args.step),
                                            ("small", args.n_small, args.small_step)) for i in range(n)]
    base = mb.load_campaign()
    t0 = time.perf_counter()
    recs = []
    with dask_client(None, args.workers) as client:
        t_cluster = time.perf_counter() - t0
        base_f = client.scatter(base, broadcast=True)
        futs = [client.submit(one_history, base_f, s, i, step, *seeds(args.seed, s, i), pure=False,
                              key=f"history-{s}-{i}") for s, i, step in jobs]
        last = time.perf_counter()
        print(f"{len(jobs)} histories on {args.workers} workers (cluster up in {t_cluster:.1f} s)", flush=True)
        for fut in as_completed(futs):
            recs.append(fut.result())
            fut.release()
            now = time.perf_counter()
            if now - last >= PROGRESS_EVERY_S or len(recs) == len(jobs):
                last = now
                el = now - t0
                c = Counter(r["scenario"] for r in recs)
                fa = sum(r.get("any_flag", False) for r in recs if r["scenario"] == "null")
                det = sum(r.get("detected", False) for r in recs if r["scenario"] == "step")
                err = sum(r["error"] is not None for r in recs)
                print(f"[{el / 60:5.1f} min] {len(recs)}/{len(jobs)} done (null {c['null']}, step {c['step']}, "
                      f"small {c['small']}); null flagged {fa}, 40″ detected {det}, errors {err}; "
                      f"ETA {el / len(recs) * (len(jobs) - len(recs)) / 60:.1f} min", flush=True)
    wall = time.perf_counter() - t0
    after = provenance()
    recs.sort(key=lambda r: (SCENARIOS[r["scenario"]], r["index"]))
    res = {s: summarise([r for r in recs if r["scenario"] == s], s) for s in SCENARIOS
           if any(r["scenario"] == s for r in recs)}

    doc = {"command": "python bench/history_alarms.py " + " ".join(
               f"--{k.replace('_', '-')} {v}" for k, v in vars(args).items() if k != "output") + f" -o {args.output}",
           "dates": [d.date().isoformat() for d in DATES], "step_quantity": STEP_QUANTITY,
           "step_date": DATES[STEP_AT].date().isoformat(), "alpha": hfit.ALPHA,
           "trend_bayes_factor": hfit.TREND_BAYES_FACTOR, "workers": args.workers, "cpu_count": os.cpu_count(),
           "python": platform.python_version(), "wall_s": wall, "cluster_start_s": t_cluster,
           "compute_s": float(sum(r["seconds"] for r in recs)), "provenance_start": before,
           "sources_changed_during_run": before["source_sha256_16"] != after["source_sha256_16"],
           "results": res, "histories": recs}
    Path(args.output).write_text(json.dumps(doc, indent=1, default=str) + "\n")

    print()
    print(f"{len(recs)} histories (5 campaigns, 91 days apart), trend=\"auto\", α = {hfit.ALPHA}; "
          f"{args.workers} workers, wall time {wall / 60:.1f} min "
          f"({doc['compute_s'] / max(len(recs), 1):.2f} s of fit per history); Clopper–Pearson 95 % intervals")
    print()
    print("| scenario | histories | any flag | detected (beta_CZ, 4th date) | extra flag | spurious trend |")
    print("|---|---:|---|---|---|---|")
    names = {"null": "no change", "step": f"beta_CZ step {args.step:g}″",
             "small": f"beta_CZ step {args.small_step:g}″"}
    for s, r in res.items():
        hist = f"{r['histories']}" + (f" ({r['errors']} failed)" if r["errors"] else "")
        label = "**false alarm** " if s == "null" else ""
        print(f"| {names[s]} | {hist} | {label}{pct(r['any_flag'])} | {pct(r['detected']) if 'detected' in r else '–'} "
              f"| {pct(r['extra_flag']) if 'extra_flag' in r else '–'} | {pct(r['spurious_trend'])} |")
    print()
    for s, r in res.items():
        line = (f"{names[s]}: per-pair flag rate {pct(r['pair_flag_rate'])}; flagged pairs {r['flagged_pairs'] or '{}'}; "
                f"trended {r['trended_deviations'] or '{}'}")
        if "target_delta" in r:
            line += (f"; estimated step {r['target_delta']['mean']:.1f}″ ± {r['target_delta']['sd'] or 0:.1f}″; "
                     f"beta_CZ flagged at a wrong date {pct(r['beta_CZ_wrong_date'])}")
        print(line)
    if doc["sources_changed_during_run"]:
        print("WARNING: the package's history sources changed during the run (see the JSON's provenance)")
    print(f"\nJSON: {args.output}")


if __name__ == "__main__":
    main()
