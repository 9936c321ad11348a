"""The thesis' campaign keys: ``[ballbar]`` and ``[probe]`` of a campaign in its format (thesis Tables 4.2–4.4,
5.1/5.2), read into the engine's dataclasses with the validation of every key.

The ball bar's tool set-ups by their lever arms (``R_B_mm``, ``Z_T_mm``, ``X_T_mm``) and W-ball mounts (``Z_C_mm``,
``R_C_mm``), its runs of the 12 thesis patterns with their reading convention; the touch probe's ``[probe.b_axis]``
(styli at indexed B angles) and ``[probe.c_axis]`` (a sphere at indexed C angles), their centres or DPRNT files.
The engine reads the rest of the campaign (:mod:`mtmcal_bayes.io.campaign_reader`) and asks the machine for these
(its ``campaign_sections`` and ``probe_owners``).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np

from ... import units
from ...campaign import Ballbar, BAxisProbe, CAxisProbe, Machine, Mount, PlannedRun, Probe, Run, Setup, Stylus
from ...conventions import ConventionError, check_run, run_convention, run_matrix
from ...io.machine_reader import description_of
from ...io.measurement_sections import read_campaign_convention, read_convention
from ...io.planned_runs import PLANNED_KEYS as PLANNED_RUN_KEYS
from ...io.planned_runs import planned_in_order, planned_run
from ...io.probe_readings import probe_readings
from ...io.toml_reader import TomlReader, kind_of
from ...io.traces import read_trace
from ...patterns import COMPONENTS, CR_GEOMETRIES, PATTERNS, mount_conflict
from .translation import complete

#: the keys of a run's data: a planned run has none of them
DATA_KEYS = ("ex_um", "ey_um", "ez_um", "trace_csv")


#: the keys only a planned run (``planned = true``) has
PLANNED_KEYS = (*PLANNED_RUN_KEYS, "length_mm")


def campaign_sections(r: TomlReader, doc: dict, machine: Machine, base_dir: Path | None) -> tuple[Ballbar, Probe]:
    """``[ballbar]`` and ``[probe]`` in the thesis' campaign format (its lever arms R_B, Z_T, X_T, Z_C, R_C; the
    probe's ``[probe.c_axis]`` and ``[probe.b_axis]``, thesis Tables 4.2–4.4, 5.1–5.2)."""
    probe_t = r.table(doc, "probe", "", required=False)
    ballbar = _ballbar(r, r.table(doc, "ballbar", ""), base_dir, description_of(machine))
    return ballbar, _probe(r, probe_t, base_dir) if probe_t is not None else None


def _ballbar(r: TomlReader, t: dict, base_dir: Path | None, desc) -> Ballbar:
    P = "ballbar"
    r.check_keys(t, {"instrument", "length_mm", "accuracy_um", "feed_mm_per_min", "cr_geometry", "convention",
                     "alternative_reason", "setups", "mounts", "runs"}, P)
    convention = read_campaign_convention(r, t, P, example="B0=+X,B90=+Z")
    cr_geometry = r.string(t, "cr_geometry", P, default="RC-LB")
    if cr_geometry not in CR_GEOMETRIES:
        r.fail(f"{P}.cr_geometry", f"unknown CR geometry {cr_geometry!r} (expected {' or '.join(CR_GEOMETRIES)})")
    length = r.number(t, "length_mm", P, positive=True)
    accuracy = units.to_internal(r.number(t, "accuracy_um", P, positive=True), "um")
    feed = r.number(t, "feed_mm_per_min", P, required=False, positive=True)

    setups: dict[str, Setup] = {}
    for sid, path, s in r.subtables(t, "setups", P, allowed={"R_B_mm", "Z_T_mm", "X_T_mm"}, what="tool setup"):
        setups[sid] = Setup(sid, r.number(s, "R_B_mm", path, positive=True),
                            r.number(s, "Z_T_mm", path), r.number(s, "X_T_mm", path))
    _distinct_tool_lengths(r, [(f"{P}.setups.{s.id}", s.R_B, s.Z_T) for s in setups.values()])

    mounts: dict[str, Mount] = {}
    for mid, path, m in r.subtables(t, "mounts", P, allowed={"Z_C_mm", "R_C_mm"}, what="W-ball mount"):
        mounts[mid] = Mount(mid, r.number(m, "Z_C_mm", path, nonnegative=True),
                            r.number(m, "R_C_mm", path, nonnegative=True))

    raw_runs = t.get("runs", [])  # absent: a machine with set-ups and mounts but nothing measured or planned yet
    if not isinstance(raw_runs, list) or not all(isinstance(x, dict) for x in raw_runs):
        r.fail(f"{P}.runs", "expected one or more [[ballbar.runs]] tables")
    items = [_run(r, x, f"{P}.runs[{i}]", setups=setups, mounts=mounts, base_dir=base_dir, L_B=length,
                  cr_geometry=cr_geometry) for i, x in enumerate(raw_runs)]
    _distinct_runs(r, items, P)
    runs = [x for x in items if isinstance(x, Run)]
    planned = planned_in_order(r, [(i, x) for i, x in enumerate(items) if isinstance(x, PlannedRun)], P)
    bb = Ballbar(length, accuracy, r.string(t, "instrument", P), feed, setups, mounts, runs, cr_geometry, convention,
                 planned)
    complete(bb, desc)
    for i, run in enumerate(items):
        try:
            check_run(run, bb) if isinstance(run, Run) else run_matrix(run, bb)
        except ConventionError as err:
            r.fail(f"{P}.runs[{i}].convention" if run.convention else f"{P}.convention", str(err))
    _reading_choice(r, t, items, bb)
    return bb


def _reading_choice(r: TomlReader, t: dict, items: list[Run | PlannedRun], bb: Ballbar) -> None:
    """Check each run's ``alternative_convention`` as its ``convention`` is checked, and that it reads the run
    otherwise; set ``bb.alternative_reason`` (one line, only where some run names an alternative)."""
    P = "ballbar"
    for i, run in enumerate(items):
        if not isinstance(run, Run) or run.alternative_convention is None:
            continue
        key = f"{P}.runs[{i}].alternative_convention"
        other = dataclasses.replace(run, convention=run.alternative_convention)
        try:
            check_run(other, bb)
        except ConventionError as err:
            r.fail(key, str(err))
        if np.allclose(run_matrix(other, bb), run_matrix(run, bb)):
            r.fail(key, f"{run.alternative_convention!r} reads run {run.label} as its reading "
                   f"({run_convention(run, bb)!r}) does: an alternative reads it otherwise")
    reason = r.string(t, "alternative_reason", P).strip()
    if "\n" in reason:
        r.fail(f"{P}.alternative_reason", "expected one line (it is shown beside every number that rests on the choice)")
    if reason and not bb.reading_choices():
        r.fail(f"{P}.alternative_reason", "no run names an alternative_convention: there is no choice of reading to "
               "give a reason for")
    bb.alternative_reason = reason


def _distinct_tool_lengths(r: TomlReader, items: list[tuple[str, float, float]]) -> None:
    """Two tool lengths that are equal make the second one carry no information."""
    for i, (pa, rb_a, zt_a) in enumerate(items):
        for pb, rb_b, zt_b in items[i + 1:]:
            if rb_a == rb_b:
                r.fail(f"{pb}.R_B_mm", f"equal to {pa}.R_B_mm ({rb_a:g} mm): a second tool length "
                       "equal to the first carries no information")
            if zt_a == zt_b:
                r.fail(f"{pb}.Z_T_mm", f"equal to {pa}.Z_T_mm ({zt_a:g} mm) although R_B differs: "
                       "Z_T + R_B must stay constant between tool lengths")


def _distinct_runs(r: TomlReader, runs: list[Run | PlannedRun], path: str) -> None:
    """Two runs of one pattern, setup and mount are refused (``docs/campaign-format.md``, "Duplicate runs"):
    merged they would pass two sessions, perhaps a re-clamped ball, for repeats of one measurement, whose
    repeat sd the likelihood takes as the run's repeatability.  Measured and planned runs alike (the file's
    order, ``runs`` indexing ``[[ballbar.runs]]``)."""
    first: dict[tuple[str, str, str], int] = {}
    for i, run in enumerate(runs):
        j = first.setdefault((run.pattern, run.setup, run.mount), i)
        if j != i:
            if isinstance(run, PlannedRun) or isinstance(runs[j], PlannedRun):
                where = "plan one run with all its repeats (repeats = N)"
                if isinstance(runs[j], Run):
                    where = "a run already measured is not planned again on the same placement"
            else:
                arrays = ('trace_csv = ["a.csv", "b.csv"]' if run.trace_csv or runs[j].trace_csv
                          else f"{COMPONENTS[run.pattern][0]}_um = [..., ...]")
                where = f"put all repeats of one measurement in one run's arrays ({arrays})"
            r.fail(f"{path}.runs[{i}]", f"repeats {path}.runs[{j}] (pattern {run.pattern}, setup {run.setup!r}, "
                   f"mount {run.mount!r}): {where}; if the ball was re-clamped, give it its own [{path}.mounts.<id>]")


def _run(r: TomlReader, t: dict, path: str, *, setups, mounts, base_dir, L_B: float,
         cr_geometry: str) -> Run | PlannedRun:
    r.check_keys(t, {"pattern", "setup", "mount", "convention", "alternative_convention", "planned", *DATA_KEYS,
                     *PLANNED_KEYS}, path)
    planned = t.get("planned", False)
    if not isinstance(planned, bool):
        r.fail(f"{path}.planned", "expected true (a run planned but not yet measured) or false, got "
               f"{kind_of(planned)}")
    if not planned:
        for key in PLANNED_KEYS:
            if key in t:
                r.fail(f"{path}.{key}", "only a planned run (planned = true) has this key; a measured run gives its "
                       "repeats as arrays (ex_um = [..., ...]) or trace_csv")
    pattern = r.string(t, "pattern", path, required=True)
    if pattern not in PATTERNS:
        r.fail(f"{path}.pattern", f"unknown pattern {pattern!r} (expected one of {' '.join(PATTERNS)})")
    setup = r.string(t, "setup", path, required=True)
    if setup not in setups:
        r.fail(f"{path}.setup", f"names setup {setup!r}, which is not in [ballbar.setups] "
               f"(have: {', '.join(setups)})")
    mount = r.string(t, "mount", path, required=True)
    if mount not in mounts:
        r.fail(f"{path}.mount", f"names mount {mount!r}, which is not in [ballbar.mounts] "
               f"(have: {', '.join(mounts)})")
    if conflict := mount_conflict(pattern, mount, mounts[mount].R_C):
        r.fail(f"{path}.mount", conflict)
    if planned:
        if "alternative_convention" in t:
            r.fail(f"{path}.alternative_convention", "a planned run has no offsets to read another way; give it once "
                   "the run is measured")
        return _planned_run(r, t, path, pattern=pattern, setup=setup, mount=mount, L_B=L_B)
    repeats = {}
    for c in ("ex", "ey", "ez"):
        key = f"{c}_um"
        if key in t:
            if c not in COMPONENTS[pattern]:
                r.fail(f"{path}.{key}", f"pattern {pattern} has no component {c} "
                       f"(it gives {' and '.join(COMPONENTS[pattern])})")
            repeats[c] = units.to_internal(r.array(t, key, path, (None,)), "um")
            too_big = np.flatnonzero(np.abs(repeats[c]) >= L_B)
            if too_big.size:  # also keeps the models and the planner away from overflow
                i = int(too_big[0])
                r.fail(f"{path}.{key}[{i}]", f"{units.from_internal(repeats[c][i], 'um'):g} µm is not below the "
                       f"bar length L_B = {L_B:g} mm: not an eccentricity")
    traces = rms = None
    if "trace_csv" in t:
        if repeats:
            r.fail(f"{path}.trace_csv", "a run carries either eccentricity repeats or traces, not both")
        raw = t["trace_csv"]
        traces = [raw] if isinstance(raw, str) else raw
        if not isinstance(traces, list) or not traces or not all(isinstance(x, str) and x for x in traces):
            r.fail(f"{path}.trace_csv", "expected a file name or an array of file names")
        extracted, rms = [], []
        for name in traces:
            fpath = (base_dir / name) if base_dir is not None else Path(name)
            if not fpath.exists():
                r.fail(f"{path}.trace_csv", f"trace file {str(fpath)!r} not found")
            if fpath.is_dir():
                r.fail(f"{path}.trace_csv", f"trace file {str(fpath)!r} is a directory")
            ex = read_trace(fpath, pattern, L_B, cr_geometry)
            extracted.append(ex.values)
            rms.append(ex.rms)
        repeats = {c: np.array([e[c] for e in extracted]) for c in COMPONENTS[pattern]}
    if not repeats:
        r.fail(path, f"no eccentricities: give {' and/or '.join(c + '_um' for c in COMPONENTS[pattern])} "
               "or trace_csv")
    return Run(pattern, setup, mount, repeats, traces, rms, read_convention(r, t, path),
               read_convention(r, t, path, "alternative_convention"))


def _planned_run(r: TomlReader, t: dict, path: str, *, pattern: str, setup: str, mount: str,
                 L_B: float) -> PlannedRun:
    """A run with ``planned = true``: :func:`.planned_runs.planned_run`, with its reading convention and a bar length
    other than the campaign's."""
    data = [k for k in DATA_KEYS if k in t]
    if data:
        r.fail(f"{path}.planned", f"planned = true but the run has data ({', '.join(data)}): once it is measured, "
               "delete planned and repeats")
    run = planned_run(r, t, path, pattern=pattern, setup=setup, mount=mount)
    length = r.number(t, "length_mm", path, required=False, positive=True)
    run.convention = read_convention(r, t, path)
    run.length = None if length == L_B else length
    return run


def _probe(r: TomlReader, t: dict, base_dir: Path | None) -> Probe:
    P = "probe"
    r.check_keys(t, {"instrument", "repeatability_um", "c_axis", "b_axis"}, P)
    rep = r.number(t, "repeatability_um", P, required=False, positive=True)
    probe = Probe(r.string(t, "instrument", P), units.to_internal(rep, "um") if rep is not None else None)
    b = r.table(t, "b_axis", P, required=False)
    if b is not None:
        path = f"{P}.b_axis"
        r.check_keys(b, {"X_T_mm", "Z_C_mm", "angles_deg", "styli"}, path)
        angles = r.array(b, "angles_deg", path, (None,))
        if len(np.unique(angles)) < 2:
            r.fail(f"{path}.angles_deg", f"needs at least two different B angles (only differences between indexed "
                   f"positions inform the deviations), got [{', '.join(f'{a:g}' for a in angles)}]")
        bax = BAxisProbe(r.number(b, "X_T_mm", path), angles, Z_C=r.number(b, "Z_C_mm", path, required=False))
        for sid, sp, st in r.subtables(b, "styli", path, what="stylus",
                                       allowed={"R_B_mm", "nominal_mm", "centres_mm", "dprnt", "ball_radius_mm"}):
            centres, cov, files = probe_readings(r, st, sp, len(angles), base_dir=base_dir, position="angle")
            bax.styli[sid] = Stylus(sid, r.number(st, "R_B_mm", sp, positive=True),
                                    r.array(st, "nominal_mm", sp, (len(angles), 3), required=False), centres,
                                    ball_radius=r.number(st, "ball_radius_mm", sp, required=False, nonnegative=True,
                                                         default=0.0),
                                    dprnt=files, centre_cov=cov)
        for i, (sa, a) in enumerate(bax.styli.items()):
            for sb, bb in list(bax.styli.items())[i + 1:]:
                if a.R_B == bb.R_B:
                    r.fail(f"{path}.styli.{sb}.R_B_mm", f"equal to styli.{sa}.R_B_mm ({a.R_B:g} mm): "
                           "a second stylus length equal to the first carries no information")
        probe.b_axis = bax
    c = r.table(t, "c_axis", P, required=False)
    if c is not None:
        path = f"{P}.c_axis"
        r.check_keys(c, {"R_C_mm", "Z_C_mm", "axis_xy_mm", "angles_deg", "centres_mm", "dprnt", "stylus", "R_B_mm",
                         "ball_radius_mm", "datum"}, path)
        angles = r.array(c, "angles_deg", path, (None,))
        if len(np.unique(np.mod(angles, 360.0))) < 3:
            r.fail(f"{path}.angles_deg", f"needs at least three different C angles (a circle through the sphere "
                   f"centres), got [{', '.join(f'{a:g}' for a in angles)}]")
        centres, cov, files = probe_readings(r, c, path, len(angles), base_dir=base_dir, position="angle")
        stylus = r.string(c, "stylus", path, default="") or None
        R_B = r.number(c, "R_B_mm", path, required=False, positive=True)
        if stylus is not None:
            if probe.b_axis is None or stylus not in probe.b_axis.styli:
                have = ", ".join(probe.b_axis.styli) if probe.b_axis else "none"
                r.fail(f"{path}.stylus", f"no stylus {stylus!r} in [probe.b_axis.styli] (have: {have})")
            if R_B is not None:
                r.fail(f"{path}.R_B_mm", "give either stylus (a stylus of [probe.b_axis.styli]) or R_B_mm, not both")
        datum = r.string(c, "datum", path, default="machine")
        if datum not in ("machine", "first"):
            r.fail(f"{path}.datum", f"unknown datum {datum!r} (expected \"machine\": the readings are machine "
                   "coordinates with the C axis at axis_xy_mm, or \"first\": the reading frame was zeroed on the sphere)")
        probe.c_axis = CAxisProbe(
            r.number(c, "R_C_mm", path, positive=True), r.number(c, "Z_C_mm", path, nonnegative=True),
            r.array(c, "axis_xy_mm", path, (2,)), angles, centres, stylus=stylus, R_B=R_B,
            ball_radius=r.number(c, "ball_radius_mm", path, required=False, nonnegative=True, default=0.0),
            datum=datum, dprnt=files, centre_cov=cov)
    return probe


def probe_owners(machine: Machine | None, probe: Probe) -> set[str]:
    """The owners of the probe nuisance terms in the thesis' campaign format (its styli, ``c_axis``, ``b_axis``)."""
    return {o for o, _ in probe.nuisance_terms()}
