"""Write the probe-only campaigns of the controller cycles' measurement (tests/test_controller_cycles.py,
docs/_controller_cycles_section.md): one calibration sphere probed at indexed positions of both rotary axes, as
Heidenhain KinematicsOpt (Cycle 451) and Siemens CYCLE996 do, on the built-in trunnion and head-head types.

Each axis is swept over four indexed positions with the other axis at 0 and at one tilted or turned pose; the
stylus is 150 mm long; one reading per position, the probe's repeatability 1 µm.  The readings are simulated from
the truth of the demo campaigns (examples/machines/<type>.toml) through the chain with the probe's scatter
(seed 1).  Run from the project root: ``python tests/data/controller_cycles/make_campaigns.py``.

The cycles work with a calibrated probe, so each campaign's machine is its built-in type with ``deviations`` listed
(``<type>-calibrated.toml`` beside it, written here): §19's set, those the computed default selection (SPEC §21)
leaves out as the stylus' own length or the sphere's placement included, so that what a calibrated stylus
determines can be stated.
"""

import re
from pathlib import Path

import mtmcal_bayes as mb
from mtmcal_bayes.datasets import builtin_text

HERE = Path("tests/data/controller_cycles")  # relative: the campaigns name their source

#: type -> (sphere centre at the home pose (mm), sweeps: (swept axis, its angles, held axis, held angles))
CASES = {
    "trunnion": ([0.0, 100.0, 0.0],          # 50 mm above the table surface, 100 mm off the A and C lines
                 [("A", [0, -30, -60, -90], "C", [0, 90]), ("C", [0, 90, 180, 270], "A", [0, -60])]),
    "head-head": ([0.0, 0.0, -250.0],        # on the table under the C line; the stylus centre 300 mm below A
                  [("A", [-60, -20, 20, 60], "C", [0, 90]), ("C", [0, 90, 180, 270], "A", [0, 45])]),
}
#: type -> the deviations the campaigns estimate (the built-in description's, with these listed)
LISTED = {
    "trunnion": ["E_Y0A", "E_Z0A", "E_B0A", "E_C0A", "E_A0A", "E_X0C", "E_Y0C", "E_A0C", "E_B0C", "E_C0C"],
    "head-head": ["E_X0C", "E_Y0C", "E_A0C", "E_B0C", "E_C0C", "E_Y0A", "E_Z0A", "E_B0A", "E_C0A", "E_A0A",
                  "E_Y(0C1)A", "E_B(0C1)A", "E_Z(0C1)A"],
}
TRUTH = {
    "trunnion": dict(E_Y0A_um=15.0, E_Z0A_um=-10.0, E_B0A_arcsec=8.0, E_C0A_arcsec=-12.0, E_A0A_arcsec=20.0,
                     E_X0C_um=-6.0, E_Y0C_um=9.0, E_A0C_arcsec=-5.0, E_B0C_arcsec=7.0, E_C0C_arcsec=0.0),
    "head-head": {"E_X0C_um": 8.0, "E_Y0C_um": -12.0, "E_A0C_arcsec": 10.0, "E_B0C_arcsec": -6.0,
                  "E_C0C_arcsec": 0.0, "E_Y0A_um": 10.0, "E_Z0A_um": -15.0, "E_B0A_arcsec": -8.0,
                  "E_C0A_arcsec": 14.0, "E_A0A_arcsec": 18.0, "E_Y(0C1)A_um": 6.0, "E_B(0C1)A_arcsec": -9.0,
                  "E_Z(0C1)A_um": 20.0},
}


def poses(sweeps) -> tuple[list[float], list[float]]:
    """The indexed positions ``(A angles, C angles)`` of the sweeps, each pose once, in sweep order."""
    out: list[tuple[float, float]] = []
    for axis, angles, _, held in sweeps:
        for h in held:
            for a in angles:
                pose = (float(a), float(h)) if axis == "A" else (float(h), float(a))
                if pose not in out:
                    out.append(pose)
    return [p[0] for p in out], [p[1] for p in out]


def template(machine: str) -> str:
    """The campaign of ``machine`` with zeros for its readings and the truth it is simulated from."""
    sphere, sweeps = CASES[machine]
    a, c = poses(sweeps)
    fmt = lambda xs: "[" + ", ".join(f"{x:g}" for x in xs) + "]"  # noqa: E731
    zeros = "[[" + ", ".join("[0, 0, 0]" for _ in a) + "]]"
    truth = "\n".join(f'"{k}" = {v}' for k, v in TRUTH[machine].items())
    return f"""format = "mtmcal-campaign/1"

[machine]
name = "{machine}: the controller cycles' measurement"
description = "{machine}-calibrated.toml"

[probe]
instrument = "touch-trigger probe"
repeatability_um = 1.0

[probe.styli.S1]
length_mm = 150.0

[[probe.runs]]
id = "sphere"
stylus = "S1"
sphere_mm = {fmt(sphere)}
angles_deg = {{A = {fmt(a)}, C = {fmt(c)}}}
centres_mm = {zeros}

[truth.deviations]
{truth}
"""


def calibrated(machine: str) -> str:
    """The built-in description of ``machine`` with :data:`LISTED`'s deviations selected."""
    names = ", ".join(f'"{n}"' for n in LISTED[machine])
    head = ("# The built-in type with the deviations a calibrated probe's campaign estimates listed "
            "(make_campaigns.py)\n")
    text = builtin_text(f"machines/{machine}.toml")
    text = re.sub(r'^name = ".*"$', f'name = "{machine}: the controller cycles\' measurement"', text, count=1,
                  flags=re.M)  # the campaign's name: a saved campaign writes the description under it
    return head + text.replace("configuration = ", f"deviations = [{names}]\nconfiguration = ", 1)


if __name__ == "__main__":
    for machine in CASES:
        (HERE / f"{machine}-calibrated.toml").write_text(calibrated(machine))
        src = HERE / f"{machine}-cycle-template.toml"
        src.write_text(template(machine))
        campaign = mb.load_campaign(src)
        mb.simulate(campaign, truth=campaign.truth, model="chain", noise=True, seed=1,
                    output=HERE / f"{machine}-cycle.toml")
        src.unlink()
        print(HERE / f"{machine}-cycle.toml")
