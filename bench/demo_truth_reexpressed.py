"""The demo campaigns' truths re-expressed on the errors the computed default selection keeps (SPEC §21).

For each built-in type's demo: the stated truth (every deviation it names, nuisance terms zero, as the demo was
simulated) against the re-expressed one.  Each left-out error's value is moved onto the kept errors it acts through
(its ``weights``); what remains is fitted as the campaign's nuisance terms by least squares on the first-order model:
the least change, the tool balls' and styli's offsets and lengths weighted 10× less than the W balls' and spheres'
placements, then refitted without the terms it moves by less than 0.05 µm and without the placements the tool side's
terms can carry, while the fit stays exact.  Through the chain the two truths differ by the second order of the exact
rotations (products of the truth's angles times lever arms: a few nm), which no clean re-expression removes.
Prints the re-expressed truth as TOML and the largest difference of the predicted observations (mm), first order
and through the chain, ball bar and probe together.

    PYTHONPATH=. python bench/demo_truth_reexpressed.py [TYPE ...]
"""

from __future__ import annotations

import sys

import numpy as np

from mtmcal_bayes import api, units
from mtmcal_bayes.io import load_campaign
from mtmcal_bayes.machines.deviations import generated
from mtmcal_bayes.machines.selection import default_selection
from mtmcal_bayes.machines.space import described_space
from mtmcal_bayes.models import make_model
from mtmcal_bayes.models.jacobian import jacobian_at_zero
from mtmcal_bayes.simulation.simulate import truth_from_vector, truth_vector

TYPES = ("trunnion", "vertical-turn-mill", "head-head")


def reexpressed(t: str):
    """``(old Truth, new Truth, {model: max |Δprediction| mm}, space)`` for the demo of type ``t``."""
    c = load_campaign(api.demo_campaign(t))
    desc = c.machine.description
    sel = default_selection(desc)
    scale = {d.name: units.to_internal(1.0, d.quantity.unit) for d in generated(desc)}
    old = c.truth
    names = [d.name for d in generated(desc) if d.name in old.deviations or d.name in sel.kept]
    space = described_space(c, names, data="both")
    theta_old = truth_vector(space, old)
    dev = {k: v for k, v in old.deviations.items() if k not in sel.left_out}
    for name, value in old.deviations.items():
        for kept, a in getattr(sel.left_out.get(name), "weights", {}).items():
            dev[kept] = dev.get(kept, 0.0) + a * value * scale[kept] / scale[name]
    theta = space.vector(dev)
    along = "xyz"[desc.spindle.frame_axis]
    tool = np.array([p.group == "setup" and p.base != f"{along}T" or p.group == "probe" and p.base.endswith("S")
                     for p in space.parameters])  # the tool ball's (stylus') offset across the spindle, its length
    place = np.array([p.group == "mount" or p.group == "probe" and p.base.endswith("P") for p in space.parameters])
    linear = make_model("linear", c, space, data="both")
    J = jacobian_at_zero(linear)
    target = linear.predict(theta_old[None])[0]
    r = target - linear.predict(theta[None])[0]
    active, fit = tool | place, None
    while True:  # the least change (the tool side's terms weighted 10× less), then the terms it barely uses dropped
        weight = np.where(tool[active], 10.0, 1.0)
        x = weight * np.linalg.lstsq(J[:, active] * weight, r, rcond=1e-9)[0]
        if np.abs(J[:, active] @ x - r).max() > 1e-12:
            break
        fit = (active.copy(), x)
        small = np.flatnonzero(active)[np.abs(x) < units.to_internal(0.05, "um")]
        if not len(small):
            break
        active[small] = False
    for i in np.flatnonzero(fit[0] & place):  # a placement the tool side's terms can carry: dropped
        trial = fit[0].copy()
        trial[i] = False
        x = np.linalg.lstsq(J[:, trial], r, rcond=1e-9)[0]
        if np.abs(J[:, trial] @ x - r).max() <= 1e-12:
            fit = (trial, x)
    theta[fit[0]] += fit[1]
    theta = np.where(np.abs(theta) < units.to_internal(1e-9, "um"), 0.0, theta)
    chain = make_model("chain", c, space, data="both")
    gaps = {"first order": float(np.abs(linear.predict(theta_old[None])[0] - linear.predict(theta[None])[0]).max()),
            "chain": float(np.abs(chain.predict(theta_old[None])[0] - chain.predict(theta[None])[0]).max())}
    new = truth_from_vector(space, theta)
    new.deviations = {k: v for k, v in new.deviations.items() if k not in sel.left_out}
    return old, new, gaps, space


def _toml(truth, space) -> str:
    unit = {p.name: p.unit for p in space.parameters if p.group == "deviation"}
    lines = ["[truth.deviations]"]
    for k, v in truth.deviations.items():
        key = f"{k}_{unit[k]}"
        key = key if key.replace("_", "a").isalnum() else f'"{key}"'
        lines.append(f"{key} = {units.from_internal(v, unit[k]):.8g}")
    for group, table in (("setups", truth.setups), ("mounts", truth.mounts), ("probe", truth.probe)):
        for owner, vals in table.items():
            shown = {b: units.from_internal(v, "um") for b, v in vals.items() if abs(v) > 1e-9}
            if shown:
                lines.append(f"[truth.{group}.{owner}]")
                lines += [f"{b}_um = {x:.8g}" for b, x in shown.items()]
    return "\n".join(lines)


if __name__ == "__main__":
    for t in sys.argv[1:] or TYPES:
        old, new, gaps, space = reexpressed(t)
        print(f"== {t}: predictions differ by at most " + ", ".join(f"{v:.2e} mm ({k})" for k, v in gaps.items()))
        print(_toml(new, space))
