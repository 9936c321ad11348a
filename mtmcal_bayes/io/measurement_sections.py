"""The ball-bar and touch-probe sections of a campaign on a described machine (SPEC §19, docs/machines.md).

``[ballbar]``: ``length_mm``, ``accuracy_um``; ``[ballbar.setups.<id>] R_B_mm`` (the programmed tool length from
the spindle's ``point_mm``); ``[ballbar.mounts.<id>] position_mm`` (the W-ball centre at the home pose, on the
workpiece side); ``[[ballbar.runs]]`` with ``pattern`` (``<axis><R|T|A|X|Y|Z>``), ``setup``, ``mount``, optional
``arc_deg`` (the swivelled axis' angles: ``[start, end]`` with ``step_deg``, default the axis' own grid) and
``hold_deg`` (the other rotary axes, degrees), ``reversed`` (the T ball on the other side of the W ball),
``convention`` (how its offsets were read, as ``[ballbar]
convention`` says for every run: docs/conventions.md), and the pattern's two components as arrays of repeats
(``ex_um``, ``ey_um`` for a pattern about Z) — or, for a run planned but not yet measured, ``planned = true`` with
``repeats`` (and optionally ``minutes``, ``why``, ``order``), as ``design`` writes them.

``[probe]``: ``[probe.styli.<id>] length_mm`` (spindle point to stylus-ball centre; with ``ball_radius_mm``, to its
tip); ``[[probe.runs]]`` with ``stylus`` (or its length ``R_B_mm``: a stylus of the run's own), ``sphere_mm`` (its nominal centre at the home pose, workpiece side),
``angles_deg`` (axis letter -> list, all one length) and ``centres_mm`` (repeats × positions × 3: the commanded
X, Y, Z at which the stylus centre reached the sphere's centre).
"""

from __future__ import annotations

import functools

import numpy as np

from .. import units
from ..campaign import Ballbar, Mount, PlannedRun, Probe, ProbeRun, Run, Setup
from ..machines.description import MachineDescription
from ..conventions import CONVENTIONS, ConventionError, check_convention_name, check_run, run_matrix
from ..machines.patterns import DIRECTIONS, axis_of, components, default_arc_deg
from ..pattern_frames import chain_frame
from .planned_runs import PLANNED_KEYS, planned_in_order, planned_run
from .probe_readings import probe_readings
from .toml_reader import TomlReader, kind_of

#: bar length and accuracy of a campaign without ball-bar data (nothing reads them then)
NO_BALLBAR = (100.0, units.to_internal(0.5, "um"))


def described_ballbar(r: TomlReader, t: dict | None, desc: MachineDescription) -> Ballbar:
    """``[ballbar]`` of a described machine (absent: a probe-only campaign, no runs)."""
    P = "ballbar"
    if t is None:
        return Ballbar(*NO_BALLBAR)
    r.check_keys(t, {"instrument", "length_mm", "accuracy_um", "feed_mm_per_min", "convention", "setups", "mounts",
                     "runs"}, P)
    convention = read_campaign_convention(r, t, P, example="A0=+Y,A90=+Z")
    length = r.number(t, "length_mm", P, positive=True)
    accuracy = units.to_internal(r.number(t, "accuracy_um", P, positive=True), "um")
    feed = r.number(t, "feed_mm_per_min", P, required=False, positive=True)
    setups = {sid: Setup(sid, r.number(s, "R_B_mm", path, positive=True), 0.0, 0.0)
              for sid, path, s in r.subtables(t, "setups", P, allowed={"R_B_mm"}, what="tool setup")}
    mounts = {}
    for mid, path, m in r.subtables(t, "mounts", P, allowed={"position_mm"}, what="W-ball mount"):
        pos = r.array(m, "position_mm", path, (3,))
        mounts[mid] = Mount(mid, 0.0, 0.0, position=pos)
    raw = t.get("runs", [])
    if not isinstance(raw, list) or not all(isinstance(x, dict) for x in raw):
        r.fail(f"{P}.runs", "expected one or more [[ballbar.runs]] tables")
    items = [_run(r, x, f"{P}.runs[{i}]", desc, setups=setups, mounts=mounts) for i, x in enumerate(raw)]
    seen: dict[tuple, int] = {}
    for i, run in enumerate(items):
        key = (run.pattern, run.setup, run.mount, tuple(np.round(run.arc_deg, 9)),
               tuple(sorted((run.hold_deg or {}).items())), run.reversed)
        if key in seen:
            both = "plan one run with all its repeats (repeats = N)" if isinstance(run, PlannedRun) else \
                "put all repeats of one measurement in one run's arrays"
            r.fail(f"{P}.runs[{i}]", f"the same measurement as {P}.runs[{seen[key]}]: {both}")
        seen[key] = i
    runs = [x for x in items if isinstance(x, Run)]
    planned = planned_in_order(r, [(i, x) for i, x in enumerate(items) if isinstance(x, PlannedRun)], P)
    bb = Ballbar(length, accuracy, r.string(t, "instrument", P), feed, setups, mounts, runs, convention=convention,
                 planned=planned, pattern_frames=functools.partial(chain_frame, desc))
    for i, run in enumerate(items):
        try:
            check_run(run, bb) if isinstance(run, Run) else run_matrix(run, bb)
        except ConventionError as err:
            r.fail(f"{P}.runs[{i}].convention" if run.convention else f"{P}.convention", str(err))
    return bb


def _run(r: TomlReader, t: dict, path: str, desc: MachineDescription, *, setups, mounts) -> Run | PlannedRun:
    pattern = r.string(t, "pattern", path, required=True)
    try:
        ax = axis_of(desc, pattern)
    except ValueError as err:
        r.fail(f"{path}.pattern", str(err))
    comps = components(desc, pattern)
    r.check_keys(t, {"pattern", "setup", "mount", "arc_deg", "step_deg", "hold_deg", "reversed", "convention",
                     "planned", *PLANNED_KEYS, *(f"{c}_um" for c in comps)}, path)
    convention = read_convention(r, t, path)
    reversed_bar = t.get("reversed", False)
    if not isinstance(reversed_bar, bool):
        r.fail(f"{path}.reversed", f"expected true (the T ball on the other side of the W ball) or false, got "
               f"{kind_of(reversed_bar)}")
    planned = t.get("planned", False)
    if not isinstance(planned, bool):
        r.fail(f"{path}.planned", f"expected true (a run planned but not yet measured) or false, got {kind_of(planned)}")
    setup, mount = r.string(t, "setup", path, required=True), r.string(t, "mount", path, required=True)
    if setup not in setups:
        r.fail(f"{path}.setup", f"no tool setup {setup!r} in [ballbar.setups] (have: {', '.join(setups)})")
    if mount not in mounts:
        r.fail(f"{path}.mount", f"no mount {mount!r} in [ballbar.mounts] (have: {', '.join(mounts)})")
    arc = _arc(r, t, path, ax)
    hold = _hold(r, t, path, desc, swivelled=pattern[0])
    if planned:
        data = [f"{c}_um" for c in comps if f"{c}_um" in t]
        if data:
            r.fail(f"{path}.planned", f"planned = true but the run has data ({', '.join(data)}): once it is "
                   "measured, delete planned and repeats")
        if "length_mm" in t:
            r.fail(f"{path}.length_mm", "a described machine's campaign has one bar length ([ballbar] length_mm)")
        run = planned_run(r, t, path, pattern=pattern, setup=setup, mount=mount)
        run.arc_deg, run.hold_deg, run.convention, run.reversed = arc, hold, convention, reversed_bar
        return run
    for key in PLANNED_KEYS:
        if key in t:
            r.fail(f"{path}.{key}", "only a planned run (planned = true) has this key; a measured run gives its "
                   "repeats as arrays")
    repeats = {}
    for c in comps:
        v = r.array(t, f"{c}_um", path, (None,))
        repeats[c] = units.to_internal(v, "um")
    if len({len(v) for v in repeats.values()}) > 1:
        r.fail(f"{path}.{comps[1]}_um", f"has {len(repeats[comps[1]])} repeats, {comps[0]}_um "
               f"{len(repeats[comps[0]])}: give both components of every repeat")
    return Run(pattern, setup, mount, repeats, convention=convention, arc_deg=arc, hold_deg=hold,
               reversed=reversed_bar)


def read_campaign_convention(r: TomlReader, t: dict, path: str, *, example: str) -> str:
    """``[ballbar] convention``, the reading of every run that names none: a named one (default ``"thesis"``);
    ``example`` the geometry string the message shows for a run's own."""
    convention = r.string(t, "convention", path, default="thesis")
    if convention not in CONVENTIONS:
        r.fail(f"{path}.convention", f"unknown convention {convention!r} (expected one of {', '.join(CONVENTIONS)}; "
               f"a run reads another way with its own convention = \"{example}\", docs/conventions.md)")
    return convention


def read_convention(r: TomlReader, t: dict, path: str, key: str = "convention") -> str | None:
    """A run's reading convention (``key``), checked as a name or a geometry string; None where it gives none."""
    convention = r.string(t, key, path, default="") or None
    if convention is not None:
        try:
            check_convention_name(convention)
        except ConventionError as err:
            r.fail(f"{path}.{key}", str(err))
    return convention


def _arc(r: TomlReader, t: dict, path: str, ax) -> np.ndarray:
    if "arc_deg" not in t:
        if "step_deg" in t:
            r.fail(f"{path}.step_deg", "only with arc_deg = [start, end]")
        return default_arc_deg(ax)
    lo, hi = r.array(t, "arc_deg", path, (2,))
    step = r.number(t, "step_deg", path, required=False, positive=True, default=1.0)
    if hi <= lo:
        r.fail(f"{path}.arc_deg", f"expected [start, end] with start < end, got [{lo:g}, {hi:g}]")
    if (hi - lo) / step < 8:
        r.fail(f"{path}.step_deg", f"{step:g}° gives fewer than 9 angles over [{lo:g}, {hi:g}]°: too few to read "
               "the eccentricities from")
    if ax.travel is not None:
        t_lo, t_hi = np.rad2deg(ax.travel)
        if lo < t_lo - 1e-9 or hi > t_hi + 1e-9:
            r.fail(f"{path}.arc_deg", f"[{lo:g}, {hi:g}]° leaves the {ax.letter} travel [{t_lo:g}, {t_hi:g}]°")
    return np.arange(lo, hi + 1e-9, step)


def _hold(r: TomlReader, t: dict, path: str, desc: MachineDescription, *, swivelled: str) -> dict[str, float] | None:
    if "hold_deg" not in t:
        return None
    h = t["hold_deg"]
    if not isinstance(h, dict):
        r.fail(f"{path}.hold_deg", f"expected a table such as {{A = 0}}, got {kind_of(h)}")
    out = {}
    for letter in h:
        ax = desc.axes.get(letter)
        if ax is None or not ax.rotary or letter == swivelled:
            others = [a.letter for a in desc.rotary_axes if a.letter != swivelled]
            r.fail(f"{path}.hold_deg.{letter}", f"not a held rotary axis of this pattern (expected one of "
                   f"{', '.join(others) or 'none'})")
        out[letter] = r.number(h, letter, f"{path}.hold_deg")
    return out


def described_probe(r: TomlReader, t: dict, desc: MachineDescription, base_dir=None) -> Probe:
    """``[probe]`` of a described machine: styli and ``[[probe.runs]]`` (DPRNT files named relative to
    ``base_dir``)."""
    P = "probe"
    r.check_keys(t, {"instrument", "repeatability_um", "styli", "runs"}, P)
    rep = r.number(t, "repeatability_um", P, required=False, positive=True)
    probe = Probe(r.string(t, "instrument", P), units.to_internal(rep, "um") if rep is not None else None)
    for sid, path, s in (r.subtables(t, "styli", P, allowed={"length_mm", "ball_radius_mm"}, what="stylus")
                         if "styli" in t else ()):
        radius = r.number(s, "ball_radius_mm", path, required=False, nonnegative=True, default=0.0)
        length = r.number(s, "length_mm", path, positive=True) - radius
        if length <= 0:
            r.fail(f"{path}.ball_radius_mm", "longer than the stylus")
        probe.styli[sid] = length
    raw = t.get("runs")
    if not isinstance(raw, list) or not raw or not all(isinstance(x, dict) for x in raw):
        r.fail(f"{P}.runs", "expected one or more [[probe.runs]] tables")
    for i, x in enumerate(raw):
        probe.runs.append(_probe_run(r, x, f"{P}.runs[{i}]", desc, styli=probe.styli, number=i + 1,
                                     base_dir=base_dir))
    ids = [run.id for run in probe.runs]
    for i, rid in enumerate(ids):
        if rid in ids[:i]:
            r.fail(f"{P}.runs[{i}].id", f"{rid!r} names another run too")
    return probe


def _probe_run(r: TomlReader, t: dict, path: str, desc: MachineDescription, *, styli: dict,
               number: int, base_dir=None) -> ProbeRun:
    r.check_keys(t, {"id", "stylus", "R_B_mm", "sphere_mm", "angles_deg", "centres_mm", "dprnt"}, path)
    rid = r.string(t, "id", path, default=f"run{number}")
    if "R_B_mm" in t:  # the stylus given by its length alone: a stylus of the run's own, named after it
        if "stylus" in t:
            r.fail(f"{path}.R_B_mm", "give the stylus or its length R_B_mm, not both")
        if rid in styli:
            r.fail(f"{path}.id", f"{rid!r} names a stylus of [probe.styli] too; a run with R_B_mm names its own")
        styli[rid] = r.number(t, "R_B_mm", path, positive=True)
        stylus = rid
    else:
        stylus = r.string(t, "stylus", path, required=True)
    if stylus not in styli:
        r.fail(f"{path}.stylus", f"no stylus {stylus!r} in [probe.styli] (have: {', '.join(styli) or 'none'})")
    sphere = r.array(t, "sphere_mm", path, (3,))
    a = t.get("angles_deg")
    if not isinstance(a, dict) or not a:
        r.fail(f"{path}.angles_deg", "expected a table of rotary axis -> list of angles, e.g. {A = [0, -30], C = [0, 90]}")
    angles = {}
    for letter in a:
        ax = desc.axes.get(letter)
        if ax is None or not ax.rotary:
            r.fail(f"{path}.angles_deg.{letter}", f"not a rotary axis of this machine "
                   f"({', '.join(x.letter for x in desc.rotary_axes)})")
        angles[letter] = r.array(a, letter, f"{path}.angles_deg", (None,))
    sizes = {len(v) for v in angles.values()}
    if len(sizes) > 1:
        r.fail(f"{path}.angles_deg", "every axis needs one angle per position: the lists differ in length")
    n_pos = sizes.pop()
    if n_pos < 2:
        r.fail(f"{path}.angles_deg", "needs at least two indexed positions (only differences between positions inform "
               "the deviations)")
    centres, cov, files = probe_readings(r, t, path, n_pos, base_dir=base_dir)
    return ProbeRun(rid, stylus, sphere, {k: units.to_internal(v, "deg") for k, v in angles.items()}, centres,
                    dprnt=files, centre_cov=cov)


__all__ = ["described_ballbar", "described_probe", "DIRECTIONS"]
