"""Where a report's CPU goes: each drawing job's CPU time (user and system), wall time and page faults, and the
report's process against its drawing processes.

    python bench/report_jobs.py [--machine trunnion] [--runs 3] [--seed 1]

Runs ``mtmcal-bayes report`` in a fresh process per run (the command line's own settings: one BLAS thread, no
cyclic collector), each drawing job timed inside the process that runs it.  Prints, per job, the median over the
runs of CPU (user + system, s), wall (s) and minor page faults, then the median CPU of the report's own process and
of its drawing processes together.  Timings only: no output is checked here (``bench/snapshot.py`` does that).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

#: what each run executes: the report with every drawing job wrapped to time itself where it runs
_CHILD = r"""
import json, os, resource, sys, time
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
from mtmcal_bayes.reporting import drawing
_run, out = drawing._run, sys.argv.pop(1)

def timed(job, directory):
    r0, t0 = resource.getrusage(resource.RUSAGE_SELF), time.perf_counter()
    try:
        return _run(job, directory)
    finally:
        r1 = resource.getrusage(resource.RUSAGE_SELF)
        with open(out, "a") as f:
            f.write(json.dumps({"job": job[0], "wall": time.perf_counter() - t0,
                                "cpu": r1.ru_utime + r1.ru_stime - r0.ru_utime - r0.ru_stime,
                                "faults": r1.ru_minflt - r0.ru_minflt}) + "\n")

def totals():
    s, c = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    with open(out, "a") as f:
        f.write(json.dumps({"main": s.ru_utime + s.ru_stime, "children": c.ru_utime + c.ru_stime}) + "\n")

drawing._run = timed
import atexit; atexit.register(totals)
from mtmcal_bayes import cli
sys.exit(cli.main())
"""


def one_run(args, directory: str, k: int) -> list[dict]:
    log = os.path.join(directory, f"run{k}.jsonl")
    cmd = [sys.executable, "-c", _CHILD, log, "report", "-o", os.path.join(directory, f"report{k}"),
           "--seed", str(args.seed)] + (["--machine", args.machine] if args.machine else [])
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(log) as f:
        return [json.loads(line) for line in f]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--machine", default=None, help="a built-in type's demo campaign (default: the thesis campaign)")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--seed", type=int, default=1)
    args = p.parse_args()
    jobs: dict[str, list[dict]] = {}
    main_cpu, children_cpu = [], []
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.runs):
            for rec in one_run(args, tmp, k):
                if "job" in rec:
                    jobs.setdefault(rec["job"], []).append(rec)
                else:
                    main_cpu.append(rec["main"])
                    children_cpu.append(rec["children"])
    print(f"{'job':26s} {'cpu s':>7s} {'wall s':>7s} {'faults':>8s}   (medians of {args.runs} runs)")
    rows = sorted(jobs.items(), key=lambda kv: -statistics.median(r["cpu"] for r in kv[1]))
    for name, recs in rows:
        med = {key: statistics.median(r[key] for r in recs) for key in ("cpu", "wall", "faults")}
        print(f"{name:26s} {med['cpu']:7.2f} {med['wall']:7.2f} {med['faults']:8.0f}")
    jobs_cpu = sum(statistics.median(r["cpu"] for r in recs) for recs in jobs.values())
    print(f"{'every job':26s} {jobs_cpu:7.2f}")
    print(f"report process {statistics.median(main_cpu):.2f} s CPU, drawing processes "
          f"{statistics.median(children_cpu):.2f} s CPU (medians)")


if __name__ == "__main__":
    main()
