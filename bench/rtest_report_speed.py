"""``report`` and ``sample`` of each built-in type's R-test demo (docs/rtest.md, "The R-test demos"), whole process,
as ratios to the import floor (issue 43: report ≤ 3, sample ≤ 1.3 t_ref).

    python bench/rtest_report_speed.py [--repeats 5]

``t_ref`` is the import floor, ``python -c "import arviz, emcee, scipy.stats, numpy"``; each command runs as a fresh
process right after a floor run (pairs, as bench/targets.py does), in a temporary directory, and its median wall time
is divided by the floor's median.  ``sample`` takes the demo's default data (every instrument it has: the R-test) and
the default sampler; ``report`` its defaults (seed 1).  Prints one JSON document.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from targets import IMPORT_FLOOR, run  # noqa: E402  (a fresh process, its wall time and peak memory)

from mtmcal_bayes.io.machine_reader import rtest_demo_campaign  # noqa: E402

TYPES = ("integrex-i200", "vertical-turn-mill", "trunnion", "head-head")
GOALS = {"sample": 1.3, "report": 3.0}


def ratios(repeats: int) -> dict:
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        cwd = Path(tmp)
        floors, times = [], {}
        for k in range(repeats):
            for t in TYPES:
                path = rtest_demo_campaign(t)
                commands = {"sample": ["mtmcal-bayes", "sample", path, "--quiet"],
                            "report": ["mtmcal-bayes", "report", path, "-o", f"r-{t}-{k}", "--quiet"]}
                for name, argv in commands.items():
                    floors.append(run(IMPORT_FLOOR, cwd)[0])
                    times.setdefault(f"{name} {t}", []).append(run(argv, cwd)[0])
        t_ref = float(np.median(floors))
        out["t_ref_s"] = t_ref
        for key, ts in times.items():
            med, goal = float(np.median(ts)), GOALS[key.split()[0]]
            out[key] = {"wall_s": med, "ratio_to_t_ref": med / t_ref, "goal": goal, "met": med / t_ref <= goal}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    print(json.dumps(ratios(ap.parse_args().repeats), indent=1))


if __name__ == "__main__":
    main()
