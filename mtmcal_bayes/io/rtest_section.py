"""A campaign's ``[rtest]``: the R-test (SPEC §22, docs/rtest.md), read for every machine.

``[rtest]``: ``instrument``, ``repeatability_um``, the prior sds ``placement_um``, ``nest_length_um``,
``nest_offset_um``; ``[rtest.nests.<id>] length_mm`` (spindle point to nest centre), ``calibrated``; ``[[rtest.runs]]``
with ``id``, ``nest``, ``sphere_mm`` (the sphere's nominal centre at the home pose, workpiece side), ``placement``,
``angles_deg`` (rotary axis letter -> list, all one length), ``frame`` (``"tool"`` | ``"machine"``), ``zero``
(``"first"`` | ``"absolute"``) and ``displacement_um`` (repeats × positions × 3: sphere − nest).  Read into
:class:`~mtmcal_bayes.campaign.RTest` in internal units (mm, rad).
"""

from __future__ import annotations

import numpy as np

from .. import units
from ..campaign import RTEST_FRAMES, RTEST_PRIOR_SD_UM, RTEST_ZEROS, RTest, RTestNest, RTestRun
from ..machines.description import MachineDescription
from .run_angles import read_run_angles
from .toml_reader import TomlReader, kind_of

#: the keys of ``[rtest]``, of a nest and of a run
RTEST_KEYS = ("instrument", "repeatability_um", *RTEST_PRIOR_SD_UM, "sphere_mm", "nests", "runs")
#: decimals of the angles (°) and displacements (µm) written: far below any reading, and what keeps a save of a
#: loaded campaign byte for byte the one it was loaded from (the unit conversions round in the last bit)
DECIMALS = 9
NEST_KEYS = ("length_mm", "calibrated")
RUN_KEYS = ("id", "nest", "sphere_mm", "placement", "angles_deg", "frame", "zero", "displacement_um")


def read_rtest(r: TomlReader, t: dict, desc: MachineDescription | None) -> RTest:
    """``[rtest]`` of a campaign on a machine described by ``desc`` (its rotary axes name ``angles_deg``)."""
    P = "rtest"
    r.check_keys(t, set(RTEST_KEYS), P)
    if desc is None:
        r.fail(P, "the R-test needs the machine's description (a [machine] with its axes, or a built-in type)")

    def sd(key: str) -> float | None:
        v = r.number(t, key, P, required=False, positive=True)
        return units.to_internal(v, "um") if v is not None else None

    rt = RTest(r.string(t, "instrument", P), sd("repeatability_um"), sd("placement_um"), sd("nest_length_um"),
               sd("nest_offset_um"))
    for nid, path, n in r.subtables(t, "nests", P, allowed=set(NEST_KEYS), what="nest"):
        calibrated = n.get("calibrated", False)
        if not isinstance(calibrated, bool):
            r.fail(f"{path}.calibrated", f"expected true or false, got {kind_of(calibrated)}")
        rt.nests[nid] = RTestNest(r.number(n, "length_mm", path, positive=True), calibrated)
    if "sphere_mm" in t:
        rt.sphere = r.array(t, "sphere_mm", P, (3,))
    if "runs" not in t:  # an R-test still to plan for: its nests (and sphere) only
        return rt
    raw = t.get("runs")
    if not isinstance(raw, list) or not raw or not all(isinstance(x, dict) for x in raw):
        r.fail(f"{P}.runs", "expected one or more [[rtest.runs]] tables")
    for i, x in enumerate(raw):
        run = _run(r, x, f"{P}.runs[{i}]", desc, nests=rt.nests, number=i + 1)
        if any(run.id == other.id for other in rt.runs):
            r.fail(f"{P}.runs[{i}].id", f"{run.id!r} names another run too")
        rt.runs.append(run)
    return rt


def _choice(r: TomlReader, t: dict, key: str, path: str, *, allowed: tuple[str, ...]) -> str:
    v = r.string(t, key, path, default=allowed[0])
    if v not in allowed:
        r.fail(f"{path}.{key}", f"unknown {key} {v!r} (expected one of: {', '.join(allowed)})")
    return v


def _run(r: TomlReader, t: dict, path: str, desc: MachineDescription, *, nests: dict, number: int) -> RTestRun:
    r.check_keys(t, set(RUN_KEYS), path)
    rid = r.string(t, "id", path, default=f"run{number}")
    nest = r.string(t, "nest", path, required=True)
    if nest not in nests:
        r.fail(f"{path}.nest", f"no nest {nest!r} in [rtest.nests] (have: {', '.join(nests)})")
    sphere = r.array(t, "sphere_mm", path, (3,))
    placement = r.string(t, "placement", path, default="") or None
    angles, n_pos = read_run_angles(r, t, path, desc, example="{A = [0, 0], C = [0, 90]}")
    frame = _choice(r, t, "frame", path, allowed=RTEST_FRAMES)
    zero = _choice(r, t, "zero", path, allowed=RTEST_ZEROS)
    d = r.array(t, "displacement_um", path, (None, None, 3))
    if d.shape[1] != n_pos:
        r.fail(f"{path}.displacement_um", f"expected repeats x {n_pos} positions x 3 (one reading per position of "
               f"angles_deg), got {' x '.join(map(str, d.shape))}")
    return RTestRun(rid, nest, sphere, {k: units.to_internal(v, "deg") for k, v in angles.items()},
                    units.to_internal(d, "um"), frame, zero, placement)


def rtest_document(rt: RTest) -> dict:
    """``[rtest]`` as written (file units): the inverse of :func:`read_rtest`."""
    d: dict = {"instrument": rt.instrument} if rt.instrument else {}
    for key, v in (("repeatability_um", rt.repeatability), ("placement_um", rt.placement_sd),
                   ("nest_length_um", rt.nest_length_sd), ("nest_offset_um", rt.nest_offset_sd)):
        if v is not None:
            d[key] = units.from_internal(v, "um")
    if rt.sphere is not None:
        d["sphere_mm"] = [float(x) for x in rt.sphere]
    d["nests"] = {nid: {"length_mm": float(n.length), **({"calibrated": True} if n.calibrated else {})}
                  for nid, n in rt.nests.items()}
    d["runs"] = [{"id": run.id, "nest": run.nest, "sphere_mm": [float(x) for x in run.sphere],
                  **({"placement": run.placement} if run.placement is not None else {}),
                  "angles_deg": {k: [float(x) for x in np.round(units.from_internal(v, "deg"), DECIMALS)]
                                 for k, v in run.angles.items()},
                  "frame": run.frame, "zero": run.zero,
                  "displacement_um": np.round(units.from_internal(run.displacements, "um"), DECIMALS)}
                 for run in rt.runs]
    if not d["runs"]:
        del d["runs"]
    return d


__all__ = ["read_rtest", "rtest_document", "RTEST_KEYS"]
