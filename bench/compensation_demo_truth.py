"""``compensate`` on each built-in type's demo campaign against the truth the demo was simulated from
(docs/compensation.md, "Against the demo's truth").

    python bench/compensation_demo_truth.py

For each type: the 60-block program of ``examples/machines/<type>-five-axis.nc`` compensated by ``mb.compensate``
(its default posterior), then the tool point through the chain with the truth the demo's readings were simulated
from (bench/simulate_truths/<type>.toml: the machine's errors; the demo's [truth] states it re-expressed on the
errors the default selection keeps, where some became set-up terms such as a tool length), before and after:
with every deviation of the truth, and with those the compensation left at zero or the default selection leaves out as
a set-up's own term set to zero too (what the data determine).  The largest distance from the programmed point over the blocks, µm, beside the two residual bands.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

import numpy as np

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.compensation.chain_kinematics import ChainKinematics
from mtmcal_bayes.compensation.compensate import program_commands, read
from mtmcal_bayes.compensation.inverse import with_xyz
from mtmcal_bayes.io.campaign_reader import load_truth
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.machines import generated
from mtmcal_bayes.machines.chain import Chain
from mtmcal_bayes.machines.selection import default_selection

ROOT = Path(__file__).resolve().parents[1]
TYPES = ("vertical-turn-mill", "trunnion", "head-head")


def against_truth(machine: str) -> dict:
    c = mb.load_campaign(demo_campaign(machine))
    path = ROOT / "examples" / "machines" / f"{machine}-five-axis.nc"
    with tempfile.TemporaryDirectory() as tmp:
        result = mb.compensate(path, campaign=c, output=Path(tmp) / "out.nc")
    desc = c.machine.description
    kin = ChainKinematics(Chain(desc, generated(desc)), result.info["tool_length_mm"])
    q = program_commands(c, read(c, path))
    q_c = with_xyz(q, result.xyz_c)
    simulated = load_truth(ROOT / "bench" / "simulate_truths" / f"{machine}.toml", c)
    truth = {n: np.array([v]) for n, v in simulated.deviations.items()}
    # what the data do not determine: the deviations left at zero, and those the default selection leaves out as a
    # set-up's own term alone (a tool length, a sphere's placement); one that acts through kept errors is compensated
    # through them
    pure = {n for n, lo in default_selection(desc).left_out.items() if not lo.weights}
    left = {d["name"] for d in result.info["not_measured"] if d["status"] == "left at zero"} | pure
    seen = {n: v for n, v in truth.items() if n not in left}
    nominal = kin.tool_point(q, {})[0]

    def worst(commands, dev) -> float:
        return float(units.from_internal(np.linalg.norm(kin.tool_point(commands, dev)[0] - nominal, axis=-1).max(),
                                         "um"))

    return {"determined_before_um": worst(q, seen), "determined_after_um": worst(q_c, seen),
            "band_determined_p95_um": result.info["residual_determined_um"]["p95_max"],
            "all_before_um": worst(q, truth), "all_after_um": worst(q_c, truth),
            "band_p95_um": result.residual_p95_um.max(), "left_at_zero": sorted(left)}


if __name__ == "__main__":
    print(json.dumps({t: against_truth(t) for t in TYPES}, indent=1, default=float))
