"""Write the R-test demo campaign of each built-in machine type (docs/rtest.md, "The R-test demos"):
``mtmcal_bayes/datasets/machines/<type>-rtest-demo.toml``.

Per type: one sphere on the table (its position and why: :data:`SPHERES`), one nest of 150 mm (not calibrated: its
length and centring are nuisance terms), static runs in the ``tool`` frame zeroed at the first position (what most
devices export; on every built-in type that setting determines as much as any of the four, docs/rtest.md's tables):
each rotary axis indexed alone over its travel (6 positions, a full turn from 0 where it has one) with the others at
0, then each at 4 positions with the others held half way to their travel's end farther from 0 (45° on a full turn);
two repeats each.  The readings are simulated through the chain from the type's demo's own stated ``[truth]`` (its
deviations; the thesis type: Table 4.5, :data:`TABLE_4_5`) with the R-test's nuisance truths added
(:func:`rtest_truth`, :func:`zeros`), the sensors scattered by their repeatability (0.5 µm, seed :data:`SEED`) and
rounded to 0.01 µm.

R-test runs alone, not appended to the demos: a campaign of three instruments has three discrepancy scales, whose
exact posterior's grid (48 cells per scale, 110 592 in all) made ``sample`` 5–10× slower on every command and test
that takes a demo (docs/rtest.md, "Not done yet").

Run from the project root: ``python examples/machines/make_rtest_demos.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.io.campaign_reader import parse_campaign
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.io.machine_reader import builtin_description, demo_campaign
from mtmcal_bayes.io.rtest_section import rtest_document
from mtmcal_bayes.io.tomlio import dumps
from mtmcal_bayes.io.truth_table import truth_to_dict
from mtmcal_bayes.simulation.simulate import rtest_readings, simulated_rtest

OUT = Path(mb.__file__).parent / "datasets" / "machines"
SEED = 43
#: the sphere per type, mm at the home pose (workpiece side), and why there
SPHERES = {
    "integrex-i200": ([100.0, 0.0, 50.0], "100 mm off the C line, 50 mm above the table surface"),
    "vertical-turn-mill": ([60.0, 0.0, 100.0], "60 mm off the C line, 100 mm out from the chuck face: the probe's "
                                               "sphere"),
    "trunnion": ([0.0, 100.0, 0.0], "50 mm above the table surface, 100 mm off the A and the C line"),
    "head-head": ([0.0, 0.0, -250.0], "on the table under the head: the probe's sphere"),
}
NEST_MM = 150.0
ALONE, WITH = 6, 4
REPEATS = 2
#: the thesis' Table 4.5 (ball bar), the thesis type's R-test demo's truth (dx_BT = dz_BT = 0)
TABLE_4_5 = {"alpha_CZ_arcsec": 1.10, "beta_CZ_arcsec": -25.16, "alpha_XB_arcsec": -20.89,
             "beta_XB_arcsec": -24.11, "gamma_XB_arcsec": 5.63, "alpha_BT_arcsec": 9.63, "dx_CZ_um": 53.13,
             "dy_CZ_um": -45.63}
#: the R-test's own nuisance truths, µm: the sphere's placement (clamped to a few µm of its nominal centre) and the
#: nest's centring across the spindle; its length error is the tool's own where the demo's truth states one
PLACEMENT_UM = (12.0, -9.0, 6.0)
OFFSET_UM = (4.0, -3.0)


def _travel(ax) -> tuple[float, float]:
    return tuple(np.rad2deg(ax.travel)) if ax.travel is not None else (-90.0, 90.0)


def _indexed(ax, k: int) -> np.ndarray:
    lo, hi = _travel(ax)
    if hi - lo >= 360.0:
        return np.arange(k) * 360.0 / k
    return np.round(np.linspace(lo, hi, k), 9) + 0.0


def _held(ax) -> float:
    lo, hi = _travel(ax)
    return 45.0 if hi - lo >= 360.0 else 0.5 * (lo if abs(lo) > abs(hi) else hi)


def runs_text(machine: str) -> str:
    """``[rtest]`` with the static runs of ``machine`` (module docstring), readings zero."""
    axes = builtin_description(machine).rotary_axes
    runs = [(f"{ax.letter} alone", {a.letter: _indexed(ax, ALONE) if a is ax else np.zeros(ALONE) for a in axes})
            for ax in axes]
    runs += [(f"{ax.letter} with " + ", ".join(f"{a.letter} {_held(a):g}" for a in axes if a is not ax),
              {a.letter: _indexed(ax, WITH) if a is ax else np.full(WITH, _held(a)) for a in axes}) for ax in axes]
    sphere, _ = SPHERES[machine]
    doc = {"instrument": "R-test, 3 sensors", "repeatability_um": 0.5, "nests": {"N1": {"length_mm": NEST_MM}},
           "runs": [{"id": rid, "nest": "N1", "sphere_mm": sphere, "placement": "S1",
                     "angles_deg": {k: [float(x) for x in v] for k, v in angles.items()}, "frame": "tool",
                     "zero": "first", "displacement_um": [[[0.0] * 3] * len(next(iter(angles.values())))] * REPEATS}
                    for rid, angles in runs]}
    return dumps({"rtest": doc})


def rtest_truth(campaign, base_truth) -> dict:
    """The R-test's nuisance truths, µm by owner: the placement S1 (:data:`PLACEMENT_UM`, plus the probe sphere's
    placement where the demo's truth moves a left-out error onto it: a constant of the workpiece side, every sphere
    has it), the nest N1's length error (the stylus' where the truth moves the tool's own length error onto it, else
    0) and centring (:data:`OFFSET_UM`); each run's zero is added by :func:`zeros`."""
    probe = {k: v for owner in base_truth.probe.values() for k, v in owner.items()}
    place = {b: p + units.from_internal(probe.get(b[0] + "P", 0.0), "um") for b, p in zip(("xPR", "yPR", "zPR"),
                                                                                       PLACEMENT_UM)}
    nest_terms = [b for o, b in campaign.rtest.nuisance_terms(campaign.machine.description) if o == "N1"]
    nest = {"dLR": units.from_internal(probe.get("dRS", 0.0), "um")}
    nest.update(zip([b for b in nest_terms if b != "dLR"], OFFSET_UM))
    return {"S1": place, "N1": nest}


def zeros(campaign) -> dict:
    """Each run's zero, µm: its noise-free reading at its first position with zero 0 (the sensors zeroed there)."""
    d = units.from_internal(rtest_readings(campaign, campaign.truth, "chain"), "um")
    out, start = {}, 0
    for run in campaign.rtest.runs:
        out[run.id] = dict(zip(("xZR", "yZR", "zZR"), (float(v) for v in d[start])))
        start += run.positions
    return out


def truth_text(values: dict) -> str:
    lines = [""]
    for owner, terms in values.items():
        lines.append(f'[truth.rtest."{owner}"]')
        lines += [f"{k}_um = {v:.6f}" for k, v in terms.items()]
    return "\n".join(lines) + "\n"


def with_rtest(machine: str, head: str, deviations: str) -> str:
    """``head`` with the R-test runs simulated from ``deviations`` (a ``[truth.deviations]`` table) and the R-test's
    own truths (:func:`rtest_truth`, :func:`zeros`), which follow them."""
    text = head + runs_text(machine) + deviations
    c = parse_campaign(text)
    owners = rtest_truth(c, base_truth(machine))
    c = parse_campaign(text + truth_text(owners))
    owners.update(zeros(c))
    c = parse_campaign(text + truth_text(owners))
    rt = simulated_rtest(c, c.truth, "chain", noise=True, rng=np.random.default_rng(SEED))
    doc = rtest_document(rt)
    for run in doc["runs"]:
        run["displacement_um"] = np.round(np.asarray(run["displacement_um"]), 2).tolist()
    return head + dumps({"rtest": doc}) + deviations + truth_text(owners)


def base_truth(machine: str):
    """The truth of ``machine``'s demo campaign (the thesis type: Table 4.5, no nuisance terms)."""
    path = demo_campaign(machine)
    return mb.load_campaign(path).truth if path is not None else Truth()


def deviations_text(machine: str) -> str:
    """``[truth.deviations]``: the demo's own stated truth (the thesis type: :data:`TABLE_4_5`)."""
    path = demo_campaign(machine)
    values = TABLE_4_5 if path is None else truth_to_dict(mb.load_campaign(path).truth)["deviations"]
    return "\n" + dumps({"truth": {"deviations": values}})


def text_of(machine: str) -> str:
    """The R-test demo campaign of ``machine``, as written."""
    sphere, why = SPHERES[machine]
    source = (f"mtmcal_bayes/datasets/machines/{machine}-demo.toml's [truth] (its deviations)" if
              demo_campaign(machine) is not None else "the thesis' Table 4.5 (ball bar): dx_CZ - dx_BT = 53.13 um "
              "taken as\n# dx_CZ with dx_BT = 0 (the thesis' assumption), dz_BT = 0")
    head = (f"# The R-test demo of the {machine} type: R-test runs alone, simulated through the chain from\n"
            f"# {source}, with the R-test's own terms below.\n"
            f"# One sphere at {sphere} mm ({why}),\n# one nest of {NEST_MM:g} mm (not calibrated); static runs in the "
            f"tool frame zeroed at the first position,\n# two repeats each (seed {SEED}). Written by "
            "examples/machines/make_rtest_demos.py.\n\n"
            f'format = "mtmcal-campaign/1"\nmachine = "{machine}"\n\n')
    return with_rtest(machine, head, deviations_text(machine))


def write(machine: str) -> Path:
    path = OUT / f"{machine}-rtest-demo.toml"
    path.write_text(text_of(machine), encoding="utf-8")
    return path


if __name__ == "__main__":
    for m in SPHERES:
        print(write(m))
