"""Issue 44 item 4: ``design`` with targets on every determinable deviation of each built-in type, as a ratio to the
import floor t_ref (``python -c "import arviz, emcee, scipy.stats, numpy"``), goal 2.

For each built-in type, a new machine (the demo's set-ups and mounts, no runs) in two forms:

* **ball bar**: its ball-bar set-ups only (the thesis type: the built-in campaign's);
* **every instrument**: the same plus the demo's ``[probe]`` (its stylus, no runs) and the type's R-test demo's
  ``[rtest]`` (its nest, no runs) where the type has them: the design chooses among the three catalogues.  (The
  thesis type's probe record holds readings, so its campaign with every instrument adds the ``[rtest]`` alone.)

Targets 3″ for every angle and 5 µm for every length the catalogue determines one by one, relaxed by 25 % steps where
the catalogue cannot reach them (said so), σ_model's contraction 0.5 (the default).  Each ``mtmcal-bayes design``
runs as a fresh process right after a run of the import floor, ``--repeats`` pairs; the medians' ratio is printed
with the design (runs, minutes, the exact check's probability that every target is met).

``--validation``: every instrument on ``bench/design_every_instrument.py``'s machines and targets instead (the R-test's
sphere stated, the thesis machine's probe kept, the targets every instrument's catalogue determines): the designs
validated at 200 machines.

Run: ``python bench/design_speed.py [--repeats 3] [--only ballbar|all] [--validation] [TYPE ...]`` (a few minutes per
type).
"""

from __future__ import annotations

import argparse
import copy
import json
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))
from design_described import design_to, targets_for  # noqa: E402
from targets import IMPORT_FLOOR, ratio_row, run  # noqa: E402

from mtmcal_bayes import api, load_campaign, save_campaign  # noqa: E402

TYPES = ("integrex-i200", "trunnion", "head-head", "vertical-turn-mill", "nutating-head")
MACHINES = Path(__file__).resolve().parents[1] / "mtmcal_bayes" / "datasets" / "machines"
GOAL = 2.0


def new_machine(kind: str, every: bool):
    """The type's new machine (module docstring): its ball-bar set-ups, and with ``every`` its probe and R-test."""
    thesis = kind == "integrex-i200"
    c = copy.deepcopy(api.campaign_of(None if thesis else api.demo_campaign(kind)))
    c.ballbar.runs, c.ballbar.planned, c.truth, c.design = [], [], None, None
    rtest_demo = MACHINES / f"{kind}-rtest-demo.toml"
    if not every:
        c.probe = c.rtest = None
        return c
    if thesis:
        c.probe = None  # the thesis' probe record is its readings
    elif c.probe is not None:
        c.probe.runs = []
    if c.rtest is None and rtest_demo.is_file():
        c.rtest = copy.deepcopy(load_campaign(rtest_demo).rtest)
    if c.rtest is not None:
        c.rtest.runs = []
    return c


def validation_machine(kind: str):
    """``bench/design_every_instrument.py``'s new machine of ``kind`` (its R-test's sphere stated, the thesis machine's
    probe kept) and its targets: 3″ / 5 µm for every deviation every instrument's catalogue determines."""
    import design_every_instrument as validation
    from mtmcal_bayes.planning.design_instruments import other_candidates
    from mtmcal_bayes.planning.design_make import design_candidates
    from mtmcal_bayes.planning.machine_kit import planner_for

    c = validation.new_machine(kind)
    p = planner_for(c, design_candidates(c) + other_candidates(c, ["probe", "rtest"]), None)
    return c, {q: (3.0 if p.table[q].unit == "arcsec" else 5.0) for q in p.targets}


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("types", nargs="*", default=list(TYPES))
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--only", choices=("ballbar", "all"))
    ap.add_argument("--validation", action="store_true",
                    help="every instrument on bench/design_every_instrument.py's machines and targets (the designs "
                         "validated at 200 machines) instead of this module's")
    args = ap.parse_args()
    forms = ["all"] if args.validation else [f for f in ("ballbar", "all") if args.only in (None, f)]
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for kind in args.types:
            for form in forms:
                c, wanted = validation_machine(kind) if args.validation else (new_machine(kind, form == "all"), None)
                wanted = wanted or targets_for(c)
                d, relaxed = design_to(c, wanted)  # the targets the catalogue reaches (untimed)
                path = tmp / f"{kind}-{form}.toml"
                save_campaign(c, path)
                argv = ["mtmcal-bayes", "design", str(path), "--json"]
                for q, sd in {**wanted, **relaxed}.items():
                    argv += ["--target", f"{q}={sd:g}"]
                floors, walls = [], []
                for _ in range(args.repeats):
                    floors.append(run(IMPORT_FLOOR, tmp)[0])
                    wall, _, stdout = run(argv, tmp)
                    walls.append(wall)
                doc = json.loads(stdout)
                floors.sort(), walls.sort()
                t_ref, wall = floors[len(floors) // 2], walls[len(walls) // 2]
                row = ratio_row(wall, t_ref, GOAL)
                instruments = sorted({r.get("instrument", "ballbar") for r in doc["runs"]})
                out[f"{kind}/{form}"] = {**row, "runs": len(doc["runs"]), "minutes": doc["total_minutes"],
                                         "probability_targets_met": doc["probability_targets_met"],
                                         "instruments": instruments, "targets": len(wanted),
                                         "relaxed": {q: round(v, 3) for q, v in relaxed.items()}}
                print(f"{kind:20s} {form:8s} {wall:6.2f} s / t_ref {t_ref:.2f} s = {row['ratio_to_t_ref']:.2f} "
                      f"(goal {GOAL:g}: {'met' if row['met'] else 'MISSED'})  {len(doc['runs'])} runs "
                      f"({', '.join(instruments)}), {doc['total_minutes']:.0f} min, all targets met in "
                      f"{doc['probability_targets_met']:.0%} of the check's machines"
                      + (f"; relaxed: {', '.join(relaxed)}" if relaxed else ""), flush=True)
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
