"""Described machines (SPEC §19): each built-in type's demo campaign through ``sample`` and ``report`` as ratios
to the import floor, and the chain model's batch throughput against ``htm-literal`` on the thesis machine.

    python bench/machines.py [--repeats 3]

* ``t_ref`` is the import floor, ``python -c "import arviz, emcee, scipy.stats, numpy"``; each command runs as a
  fresh process, alternating with the floor (as ``bench/targets.py`` does), and its median wall time is divided by
  the floor's median: goals (issue 36) ``sample`` ≤ 1.3 t_ref and ``report`` ≤ 3 t_ref, the thesis machine's;
* the throughput: one batch of 2 000 draws of the thesis campaign (13 deviations and every nuisance term at
  random sizes) through ``chain`` and through ``htm-literal``, alternated, median of ``--repeats``; the goal is a
  ratio chain / htm-literal ≤ 1.5.  The two agree to the last bit (tests/test_chain.py).

Prints one JSON document.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
from targets import ratio_row, run  # noqa: E402  (a fresh process, its wall time and peak memory)

TYPES = ("vertical-turn-mill", "trunnion", "head-head")
FLOOR = ["python", "-c", "import arviz, emcee, scipy.stats, numpy"]


def command_ratios(repeats: int) -> dict:
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        cwd = Path(tmp)
        floors, times = [], {}
        for _ in range(repeats):
            for t in TYPES:
                floors.append(run(FLOOR, cwd)[0])
                times.setdefault(f"sample {t}", []).append(run(["mtmcal-bayes", "sample", "--machine", t, "--quiet"],
                                                                cwd)[0])
                floors.append(run(FLOOR, cwd)[0])
                times.setdefault(f"report {t}", []).append(run(["mtmcal-bayes", "report", "--machine", t, "-o",
                                                                f"rep-{t}", "--quiet"], cwd)[0])
        t_ref = float(np.median(floors))
        out["t_ref_s"] = t_ref
        for name, ts in times.items():
            goal = 1.3 if name.startswith("sample") else 3.0
            med = float(np.median(ts))
            out[name] = ratio_row(med, t_ref, goal)
    return out


def throughput(repeats: int) -> dict:
    from mtmcal_bayes.api import campaign_of
    from mtmcal_bayes.models import make_model
    from mtmcal_bayes.plugins.thesis.kinematic import HTMModel
    from mtmcal_bayes.parameters import ParameterSpace

    c = campaign_of(None)
    space = ParameterSpace.for_campaign(c)
    theta = np.random.default_rng(1).normal(size=(2000, len(space))) * space.display_scale() * 30
    models = {"chain": make_model("chain", c, space), "htm-literal": HTMModel(c, "htm-literal", space)}
    times: dict[str, list[float]] = {k: [] for k in models}
    for _ in range(repeats):
        for name, m in models.items():
            t0 = time.perf_counter()
            m.predict(theta)
            times[name].append(time.perf_counter() - t0)
    med = {k: float(np.median(v)) for k, v in times.items()}
    return {"draws": len(theta), "seconds": med, "ratio_chain_to_htm_literal": med["chain"] / med["htm-literal"],
            "goal": 1.5}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    print(json.dumps({"throughput": throughput(args.repeats), "commands": command_ratios(args.repeats)}, indent=2))


if __name__ == "__main__":
    main()
