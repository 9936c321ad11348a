"""The demo campaigns' truths re-expressed on the errors the computed default selection keeps (SPEC §21).

For each built-in type's demo: the truth its readings were simulated from (bench/simulate_truths/<type>.toml: every
deviation it names, nuisance terms zero) against the re-expressed one.  Each left-out error's value is moved onto the kept errors it acts through
(its ``weights``); what remains is fitted as the campaign's nuisance terms by least squares on the first-order model:
the least change in units of each term's default prior sd (the re-expression the priors find most plausible: a
tool ball centred to 1 µm takes little, a W ball clamped to 35 µm or a sphere placed to 300 µm much), then refitted
without the terms it moves by less than 0.05 µm while the fit stays exact.  Through the chain the two truths differ by the second order of the exact
rotations (products of the truth's angles times lever arms: a few nm), which no clean re-expression removes.
Prints the re-expressed truth as TOML and the largest difference of the predicted observations (mm), first order
and through the chain, ball bar and probe together; then the same for the controller cycles' probe-only campaigns
(tests/data/controller_cycles), simulated from the same truths.

    PYTHONPATH=. python bench/demo_truth_reexpressed.py [TYPE ...]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from mtmcal_bayes import api, units
from mtmcal_bayes.inference.priors import DEFAULTS
from mtmcal_bayes.io import load_campaign
from mtmcal_bayes.io.campaign_reader import load_truth
from mtmcal_bayes.machines.deviations import generated
from mtmcal_bayes.machines.selection import default_selection
from mtmcal_bayes.machines.space import described_space
from mtmcal_bayes.models import make_model
from mtmcal_bayes.models.jacobian import jacobian_at_zero
from mtmcal_bayes.simulation.simulate import truth_from_vector, truth_vector

TYPES = ("trunnion", "vertical-turn-mill", "head-head")
SIMULATED = Path(__file__).resolve().parent / "simulate_truths"


def reexpressed(t: str, campaign=None):
    """``(old Truth, new Truth, {model: max |Δprediction| mm}, space)`` for the demo of type ``t`` (or the campaign at
    path ``campaign`` on that type, simulated from the same truth: the controller cycles' of tests/data)."""
    c = load_campaign(campaign or api.demo_campaign(t))
    data = "both" if c.ballbar.runs and c.probe else ("probe" if c.probe else "ballbar")
    desc = c.machine.description
    sel = default_selection(desc)
    scale = {d.name: units.to_internal(1.0, d.quantity.unit) for d in generated(desc)}
    old = load_truth(SIMULATED / f"{t}.toml", c)  # the truth the readings were simulated from
    names = [d.name for d in generated(desc) if d.name in old.deviations or d.name in sel.kept]
    space = described_space(c, names, data=data)
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
    linear = make_model("linear", c, space, data=data)
    J = jacobian_at_zero(linear)
    target = linear.predict(theta_old[None])[0]
    r = target - linear.predict(theta[None])[0]
    sd = np.array([DEFAULTS.get(p.base, (None, 1.0))[1] for p in space.parameters])
    active, fit = tool | place, None
    while True:  # the least change in units of the priors' sd (the most plausible), then the terms barely used dropped
        weight = sd[active]
        x = weight * np.linalg.lstsq(J[:, active] * weight, r, rcond=1e-9)[0]
        if np.abs(J[:, active] @ x - r).max() > 1e-12:
            break
        fit = (active.copy(), x)
        small = np.flatnonzero(active)[np.abs(x) < units.to_internal(0.05, "um")]
        if not len(small):
            break
        active[small] = False
    theta[fit[0]] += fit[1]
    theta = np.where(np.abs(theta) < units.to_internal(1e-9, "um"), 0.0, theta)
    chain = make_model("chain", c, space, data=data)
    gaps = {"first order": float(np.abs(linear.predict(theta_old[None])[0] - linear.predict(theta[None])[0]).max()),
            "chain": float(np.abs(chain.predict(theta_old[None])[0] - chain.predict(theta[None])[0]).max())}
    new = truth_from_vector(space, theta)
    new.deviations = {k: v for k, v in new.deviations.items() if k not in sel.left_out and (k in old.deviations or v)}
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


CYCLES = Path(__file__).resolve().parents[1] / "tests" / "data" / "controller_cycles"

if __name__ == "__main__":
    cases = [(t, None) for t in TYPES] + [(t, CYCLES / f"{t}-cycle.toml") for t in ("trunnion", "head-head")]
    for t, path in cases:
        if sys.argv[1:] and t not in sys.argv[1:]:
            continue
        old, new, gaps, space = reexpressed(t, path)
        t = t if path is None else path.name
        print(f"== {t}: predictions differ by at most " + ", ".join(f"{v:.2e} mm ({k})" for k, v in gaps.items()))
        print(_toml(new, space))
