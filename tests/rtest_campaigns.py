"""R-test campaigns for the tests and the bench scripts (docs/rtest.md): the text of a campaign of R-test runs, and
the one-sphere static R-test campaign of each built-in type ("What a one-sphere static R-test campaign determines").

Only TOML text is built here; the package reads it (:func:`~mtmcal_bayes.io.campaign_reader.parse_campaign`)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from mtmcal_bayes.datasets import builtin_campaign_text
from mtmcal_bayes.io.campaign_reader import parse_campaign
from mtmcal_bayes.io.machine_reader import builtin_description, demo_campaign

#: the sphere of the one-sphere campaign per built-in type, mm at the home pose (workpiece side), and why there
SPHERES = {
    "integrex-i200": ([100.0, 0.0, 50.0], "100 mm off the C line, 50 mm above the table surface"),
    "vertical-turn-mill": ([60.0, 0.0, 100.0], "60 mm off the C line, 100 mm out from the chuck face: the demo's "
                                               "probe sphere"),
    "trunnion": ([0.0, 100.0, 0.0], "50 mm above the table surface, 100 mm off the A and the C line: the "
                                    "controller cycles' sphere"),
    "head-head": ([0.0, 0.0, -250.0], "on the table under the head: the demo's probe sphere"),
    "nutating-head": ([100.0, 0.0, 50.0], "100 mm off the C line, 50 mm above the table surface: the demo's R-test "
                                          "sphere"),
}
#: the nest's length from the spindle's point, mm (not calibrated: its length and centring are nuisance terms)
NEST_MM = 150.0
#: positions of a run indexing one axis alone
ALONE = 6
#: the settings of the frame and the zero (docs/rtest.md)
SETTINGS = (("tool", "first"), ("tool", "absolute"), ("machine", "first"), ("machine", "absolute"))


def _toml_list(values) -> str:
    return "[" + ", ".join(f"{float(v):.12g}" for v in values) + "]"


def campaign_text(machine: str, runs: list[dict], *, nests: dict, extra: str = "") -> str:
    """A campaign of R-test runs on ``machine``: each run ``{id, nest, sphere, angles {letter: list}, frame, zero,
    repeats, placement?}``, zeros as its readings; ``nests`` {id: (length_mm, calibrated)}."""
    lines = ['format = "mtmcal-campaign/1"', f'machine = "{machine}"', "", "[rtest]",
             'instrument = "R-test, 3 sensors"', "repeatability_um = 0.5", ""]
    for nid, (length, calibrated) in nests.items():
        lines += [f"[rtest.nests.{nid}]", f"length_mm = {length}"] + (["calibrated = true"] if calibrated else []) + [""]
    for run in runs:
        k = len(next(iter(run["angles"].values())))
        zeros = "[" + ", ".join(["[" + ", ".join(["[0.0, 0.0, 0.0]"] * k) + "]"] * run.get("repeats", 1)) + "]"
        angles = ", ".join(f"{a} = {_toml_list(v)}" for a, v in run["angles"].items())
        lines += ["[[rtest.runs]]", f'id = "{run["id"]}"', f'nest = "{run["nest"]}"',
                  f"sphere_mm = {_toml_list(run['sphere'])}",
                  *([f'placement = "{run["placement"]}"'] if "placement" in run else []),
                  f"angles_deg = {{{angles}}}", f'frame = "{run["frame"]}"', f'zero = "{run["zero"]}"',
                  f"displacement_um = {zeros}", ""]
    return "\n".join(lines) + extra


def _travel(ax) -> tuple[float, float]:
    """An axis' travel, degrees (±90° where the description states none)."""
    return tuple(np.rad2deg(ax.travel)) if ax.travel is not None else (-90.0, 90.0)


def _indexed(ax, k: int) -> np.ndarray:
    """``k`` indexed angles over an axis' travel, degrees: a full turn from 0 where it has one, else its travel's
    ends and evenly between."""
    lo, hi = _travel(ax)
    if hi - lo >= 360.0:
        return np.arange(k) * 360.0 / k
    return np.round(np.linspace(lo, hi, k), 9) + 0.0  # + 0.0: no -0 in a printed angle


def _held(ax) -> float:
    """Where an axis is held while another is indexed with it: half way to its travel's end farther from 0 (45° on
    a full turn)."""
    lo, hi = _travel(ax)
    if hi - lo >= 360.0:
        return 45.0
    return 0.5 * (lo if abs(lo) > abs(hi) else hi)


def static_runs(machine: str, frame: str, zero: str) -> list[dict]:
    """The one-sphere static runs on ``machine``: each rotary axis indexed alone over its travel (:data:`ALONE`
    positions, the others at 0), then each indexed at 4 positions with the others held (:func:`_held`); all in one
    ``frame`` and ``zero``, one sphere (:data:`SPHERES`), one nest (:data:`NEST_MM`)."""
    axes = builtin_description(machine).rotary_axes
    sphere = SPHERES[machine][0]
    runs = []
    for ax in axes:
        runs.append({"angles": {a.letter: (_indexed(ax, ALONE) if a is ax else np.zeros(ALONE)) for a in axes},
                     "id": f"{ax.letter} alone"})
    for ax in axes:
        runs.append({"angles": {a.letter: (_indexed(ax, 4) if a is ax else np.full(4, _held(a))) for a in axes},
                     "id": f"{ax.letter} with " + ", ".join(f"{a.letter} {_held(a):g}" for a in axes if a is not ax)})
    return [dict(r, nest="N1", sphere=sphere, frame=frame, zero=zero) for r in runs]


def static_text(machine: str, frame: str = "tool", zero: str = "first", repeats: int = 1) -> str:
    """The one-sphere static R-test campaign's text (:func:`static_runs`)."""
    runs = [dict(r, repeats=repeats) for r in static_runs(machine, frame, zero)]
    return campaign_text(machine, runs, nests={"N1": (NEST_MM, False)})


def static_campaign(machine: str, frame: str = "tool", zero: str = "first"):
    """The one-sphere static R-test campaign (:func:`static_text`), parsed."""
    return parse_campaign(static_text(machine, frame, zero))


def every_setting_text(machine: str, repeats: int = 1) -> str:
    """The one-sphere static runs in each of the four settings of frame and zero (:data:`SETTINGS`), one campaign:
    one sphere placement, one nest, 4 × 4 runs (each run's id with its setting)."""
    runs = [dict(r, id=f"{r['id']} ({frame}, {zero})", repeats=repeats)
            for frame, zero in SETTINGS for r in static_runs(machine, frame, zero)]
    return campaign_text(machine, runs, nests={"N1": (NEST_MM, False)})


def with_every_instrument_text(machine: str) -> str:
    """The demo campaign of ``machine`` (the thesis campaign on the thesis type: ball bar and touch probe) with the
    R-test runs of :func:`every_setting_text` added: every instrument.  A demo with R-test runs of its own (the
    nutating head's) is every instrument as it is."""
    path = demo_campaign(machine)
    base = builtin_campaign_text()[0] if path is None else Path(path).read_text(encoding="utf-8")
    if "\n[rtest]" in base:
        return base
    rt = every_setting_text(machine)
    return base + "\n" + rt[rt.index("[rtest]"):]
