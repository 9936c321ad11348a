"""A probe-only design per built-in type (issue 44 item 1): ``design --instruments probe`` on a machine with only a
touch probe, set beside the controller cycles' measurement (docs/machines.md, "The controller cycles'
measurement").

For each type: its description with a ``[probe]`` alone (1 µm repeatability, a 150 mm stylus; no ball bar): the
sphere where the controller-cycle campaign puts it (``tests/data/controller_cycles/<type>-cycle.toml``: trunnion,
head-head), else where the type's demo probe run has it; that run is kept, measured: its readings enter the design's
posterior (every measured instrument's readings do: docs/design.md, "Every instrument"), so the design starts from
a machine probed once (``bench/design_every_instrument.py --probe`` designs the same machine new: the run replaced
by a W-ball mount at the sphere).  Targets: 3″ for every angle and 5 µm
for every length the probe catalogue determines one by one (relaxed by 25 % steps where it cannot reach them),
σ_model_probe's contraction 0.5.  Printed: the runs (axis, positions, held axes, stylus, sphere), the minutes, and
per target the design's promised sd and the exact check's share met.

Run: ``python bench/design_instruments.py [TYPE ...]`` (default every built-in type with a probe sphere).
"""

from __future__ import annotations

import copy
import sys
import time
from pathlib import Path

from mtmcal_bayes import api, units
from mtmcal_bayes.campaign import Ballbar
from mtmcal_bayes.io import load_campaign
from mtmcal_bayes.planning.design_instruments import other_candidates
from mtmcal_bayes.planning.machine_kit import planner_for

sys.path.insert(0, str(Path(__file__).parent))
from design_described import design_to

ROOT = Path(__file__).resolve().parents[1]
TYPES = tuple(sys.argv[1:]) or ("trunnion", "head-head", "vertical-turn-mill", "nutating-head")


def probe_only(kind: str):
    """The type's machine with its probe alone, no runs of any instrument but the sphere's, measured (module
    docstring)."""
    c = copy.deepcopy(api.campaign_of(api.demo_campaign(kind)))
    cycle = ROOT / "tests" / "data" / "controller_cycles" / f"{kind}-cycle.toml"
    source = load_campaign(cycle) if cycle.is_file() else c
    probe = copy.deepcopy(source.probe)
    probe.runs = probe.runs[:1]  # where the sphere sits; its readings are in the design's posterior (measured)
    c.ballbar = Ballbar(length=c.ballbar.length, accuracy=c.ballbar.accuracy)
    c.probe, c.rtest, c.truth = probe, None, None
    return c, "controller-cycle campaign" if cycle.is_file() else "demo"


def main() -> None:
    for kind in TYPES:
        t0 = time.perf_counter()
        c, where = probe_only(kind)
        p = planner_for(c, other_candidates(c, ["probe"]), None)
        targets = {q: (3.0 if p.table[q].unit == "arcsec" else 5.0) for q in p.targets}
        d, relaxed = design_to(c, targets, instruments="probe")
        s = c.probe.runs[0].sphere
        print(f"\n{kind} (sphere at ({s[0]:g}, {s[1]:g}, {s[2]:g}) mm, from the {where}): {len(d.runs)} probe runs, "
              f"{d.total_minutes:.0f} min ({time.perf_counter() - t0:.0f} s)")
        print(f"  not determined by any probe run of the catalogue: {', '.join(p.not_targeted) or 'none'}")
        if relaxed:
            print("  relaxed: " + ", ".join(f"{q} → {v:.3g}" for q, v in relaxed.items()))
        for r, m in zip(d.runs, d.minutes):
            print(f"  {r.label}: {m:.1f} min")
        share = d.check.share_met(d.goal.targets)
        for j, q in enumerate(d.targets):
            if q in targets:
                u = units.SYMBOL[d.target_units[j]]
                print(f"  {q:<12} goal {d.goal.targets[j]:.3g}{u}: check mean sd {d.check.sd_mean[j]:.3g}{u}, "
                      f"met {share[j]:.0%}")
        print(f"  σ_model_probe contraction {d.check.contraction.mean():.2f}")


if __name__ == "__main__":
    main()
