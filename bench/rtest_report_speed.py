"""``report`` and ``sample`` of each built-in type's R-test demo (docs/rtest.md, "The R-test demos"), whole process,
as ratios to the import floor (issue 43: report ≤ 3, sample ≤ 1.3 t_ref).

    python bench/rtest_report_speed.py [--repeats 5]

``t_ref`` is the import floor, ``python -c "import arviz, emcee, scipy.stats, numpy"``; each command runs as a fresh
process right after a floor run (pairs, as bench/targets.py does), in a temporary directory, and its median wall time
is divided by the floor's median.  ``sample`` takes the demo's default data (every instrument it has: the R-test) and
the default sampler; ``report`` its defaults (seed 1); the nutating head's demo (ball bar, probe and R-test) with
every instrument and with its R-test alone.  Prints one JSON document.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path


sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from targets import ratio_row, timed_against_floor  # noqa: E402  (fresh processes, each after the import floor)

from mtmcal_bayes.io.machine_reader import rtest_demo_campaign  # noqa: E402

TYPES = ("integrex-i200", "vertical-turn-mill", "trunnion", "head-head")
GOALS = {"sample": 1.3, "report": 3.0}


def ratios(repeats: int) -> dict:
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        cwd = Path(tmp)
        commands = {}
        for t in TYPES:
            path = rtest_demo_campaign(t)
            commands[f"sample {t}"] = ["mtmcal-bayes", "sample", path, "--quiet"]
            commands[f"report {t}"] = ["mtmcal-bayes", "report", path, "-o", f"r-{t}", "--quiet"]
        # the nutating head's own demo has R-test runs beside the ball bar and the probe (no separate R-test demo)
        for data in ("all", "rtest"):
            args = ["--machine", "nutating-head", "--data", data]
            commands[f"sample nutating-head --data {data}"] = ["mtmcal-bayes", "sample", *args, "--quiet"]
            commands[f"report nutating-head --data {data}"] = ["mtmcal-bayes", "report", *args, "-o",
                                                              f"r-nutating-{data}", "--quiet"]
        t_ref, times = timed_against_floor(commands, cwd, repeats)
        out["t_ref_s"] = t_ref
        for key, med in times.items():
            goal = GOALS[key.split()[0]]
            out[key] = ratio_row(med, t_ref, goal)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    print(json.dumps(ratios(ap.parse_args().repeats), indent=1))


if __name__ == "__main__":
    main()
