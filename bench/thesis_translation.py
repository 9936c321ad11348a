"""How far the thesis campaign format is from the engine's: the engine's chain on the thesis campaign translated
into positions and arcs, against the thesis plug-in's ``chain`` on its own format (issue 42, the translation).

Every one of the thesis' 12 patterns at both set-ups of the built-in campaign, its W balls placed at
``position_mm = (0 or R_C, 0, Z_C)`` (the dummy sphere of the mount's first run: X = 0 for a B pattern, R_C for a C
pattern) and its runs over the thesis' grids as ``arc_deg`` (B 0–90° by 1°, C 0–355° by 5°); deviations and nuisance
terms drawn at 50 and 10 (µm or µrad) sd.  Prints, per pattern, the largest difference of the eccentricities (µm)
and of their first-order sensitivities.

    python bench/thesis_translation.py [--draws 20] [--seed 1]
"""

from __future__ import annotations

import argparse
import copy

import numpy as np

from mtmcal_bayes.campaign import Run
from mtmcal_bayes.io import load_campaign
from mtmcal_bayes.models import make_model
from mtmcal_bayes.models.chain_models import ChainBallbarModel
from mtmcal_bayes.patterns import B_ANGLES_DEG, B_PATTERNS, C_ANGLES_DEG, COMPONENTS, PATTERNS


def translated(campaign):
    """A copy of a thesis-format campaign with each mount's ``position`` and each run's ``arc_deg`` (module doc)."""
    t = copy.deepcopy(campaign)
    first = {}
    for run in t.ballbar.runs:
        first.setdefault(run.mount, run)
    for mid, m in t.ballbar.mounts.items():
        m.position = np.array([0.0 if first[mid].pattern in B_PATTERNS else m.R_C, 0.0, m.Z_C])
    for run in t.ballbar.runs:
        run.arc_deg = B_ANGLES_DEG if run.pattern in B_PATTERNS else C_ANGLES_DEG
    return t


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=20)
    ap.add_argument("--seed", type=int, default=1)
    a = ap.parse_args()
    c = load_campaign(None)
    c.ballbar.runs = [Run(p, s, "B" if p in B_PATTERNS else "C", {k: np.zeros(1) for k in COMPONENTS[p]})
                      for s in c.ballbar.setups for p in PATTERNS]
    c.probe = None
    own = make_model("chain", c)
    engine = ChainBallbarModel(translated(c), own.space, observations=own.observations)
    p = len(own.space.parameters)
    sd = np.array([5e-5 if q.group == "deviation" else 1e-5 for q in own.space.parameters])
    theta = np.random.default_rng(a.seed).normal(0.0, 1.0, (a.draws, p)) * sd
    diff = np.abs(own.predict(theta) - engine.predict(theta)).max(axis=0) * 1e3
    h = 1e-7
    zero = np.zeros(p)
    jac = lambda m: np.array([(m.predict(zero + h * e) - m.predict(zero)) / h for e in np.eye(p)]).T  # noqa: E731
    jdiff = np.abs(jac(own) - jac(engine)).max(axis=1)
    size = np.abs(own.predict(theta)).max() * 1e3
    print(f"eccentricities up to {size:.1f} µm; largest difference per pattern (µm) and of the first-order sensitivities (mm per unit of a parameter, mm or rad):")
    for pattern in PATTERNS:
        rows = [i for i, k in enumerate(own.observations.keys) if k.pattern == pattern]
        print(f"  {pattern}  {diff[rows].max():.2e}  {jdiff[rows].max():.2e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
