"""Calibration and power of the instruments' consistency check on every built-in machine type (docs/probe.md).

    python bench/instrument_check.py [--n 200] [--seed 2] [--wide-value 0]

Calibration: ``n`` campaigns of each type's design (the thesis campaign and the three demo campaigns) simulated
from the fused linear prior without a conflict (:func:`~mtmcal_bayes.posterior.check_calibration.null_p_values`:
the wide nuisance terms at ``--wide-value`` prior sds, everything else drawn); per reading group the
Kolmogorov–Smirnov p-value of its ``n`` p-values against the uniform, their mean, and the share below 0.01 and 0.1.

Power: the campaign itself with the positions at the last angle of its first probe run's first indexed axis
(the thesis: the C-axis run at C = 270°) moved 15 µm along X, Y and Z in turn; the probe group's χ², dof and p.

Prints Markdown tables.
"""

from __future__ import annotations

import argparse
import copy
import time

import numpy as np
from scipy import stats

from mtmcal_bayes.io import load_campaign
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.posterior.check_calibration import null_p_values
from mtmcal_bayes.posterior.instrument_check import check_instruments

TYPES = ("integrex-i200", "trunnion", "vertical-turn-mill", "head-head")
SHIFT_MM = 0.015


def shifted(campaign, axis: int, shift: float = SHIFT_MM):
    """A copy of ``campaign`` whose first probe run's positions at the last angle of its first axis are moved
    ``shift`` mm along machine axis ``axis`` (0, 1, 2)."""
    c = copy.deepcopy(campaign)
    run = c.probe.runs[0]
    first = next(iter(run.angles.values()))
    run.centres[:, np.isclose(first, first[-1]), axis] += shift
    return c


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--wide-value", type=float, default=0.0)
    args = ap.parse_args()
    print(f"| type | group | dof | KS p | mean p | p < 0.01 | p < 0.1 |  (n = {args.n}, seed {args.seed})")
    print("|---|---|---|---|---|---|---|")
    power = []
    for name in TYPES:
        c = load_campaign(demo_campaign(name))
        t0 = time.perf_counter()
        df = null_p_values(c, args.n, args.seed, wide_value=args.wide_value)
        took = time.perf_counter() - t0
        for (given, group), d in df.groupby(["given", "group"], sort=False):
            p = d["p_value"].to_numpy()
            print(f"| {name} | {group} given {given} | {d['dof'].iloc[0]} | {stats.kstest(p, 'uniform').pvalue:.3g} "
                  f"| {p.mean():.3f} | {np.mean(p < 0.01):.3f} | {np.mean(p < 0.1):.3f} |")
        print(f"| {name} | ({took:.0f} s) | | | | | |")
        for axis in range(3):
            g = check_instruments(shifted(c, axis), explain=False).consistency.groups
            row = g[g["group"].str.startswith("probe")].iloc[0]
            power.append(f"| {name} | {'XYZ'[axis]} | {row['group']} | {row['chi2']:.1f} | {row['dof']} "
                         f"| {row['p_value']:.2g} |")
    print("\n| type | shift along | group | χ² | dof | p |\n|---|---|---|---|---|---|")
    print("\n".join(power))


if __name__ == "__main__":
    main()
