"""``[ballbar]`` of a campaign on any machine: the one reader of set-ups, mounts and runs (SPEC §19, §20).

The engine's keys (docs/campaign-format.md): ``length_mm``, ``accuracy_um``, ``instrument``, ``feed_mm_per_min``,
``convention``, ``alternative_reason``; ``[ballbar.setups.<id>] R_B_mm`` (the programmed tool length from the
spindle's ``point_mm``); ``[ballbar.mounts.<id>] position_mm`` (the W-ball centre at the home pose, workpiece side);
``[[ballbar.runs]]`` with ``pattern`` (``<axis><R|T|A|X|Y|Z>``), ``setup``, ``mount``, ``arc_deg`` + ``step_deg``,
``hold_deg``, ``reversed``, ``convention`` and ``alternative_convention``, and its eccentricities: the pattern's
components as arrays of repeats (``ex_um``, ``ey_um`` for a pattern about Z; one of them may be left out) or
``trace_csv`` (one ΔL trace file per repeat, fitted here) — or, planned but not yet measured, ``planned = true`` with
``repeats`` (``minutes``, ``why``, ``order``, and ``length_mm`` for a bar other than the campaign's).

A machine's plug-in may read its own keys in the place of the set-ups' and mounts' (``ballbar_keys``: the thesis'
lever arms R_B, Z_T, X_T and W-ball mounts Z_C, R_C, its ``cr_geometry``), name its patterns (``patterns``,
``pattern_components``), refuse a mount for a pattern (``mount_conflict``) and complete the ball bar in the engine's
terms (its patterns' arcs and bar sides); everything else is read here alike for every machine.  The same
``ballbar_keys`` write its keys back (``write``, ``write_setup``, ``write_mount``) for the one writer,
:mod:`.ballbar_writer`.
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import numpy as np

from .. import units
from ..campaign import Ballbar, Machine, Mount, PlannedRun, Run, Setup
from ..conventions import (
    CONVENTIONS,
    ConventionError,
    check_convention_name,
    check_run,
    run_convention,
    run_matrix,
)
from ..machines.description import MachineDescription
from ..machines.patterns import axis_of, components, default_arc_deg
from ..machines.plugins import provided
from ..pattern_frames import chain_frame
from .planned_runs import PLANNED_KEYS as PLANNED_RUN_KEYS
from .planned_runs import planned_in_order, planned_run
from .toml_reader import TomlReader, kind_of
from .traces import read_run_trace

#: bar length and accuracy of a campaign without ball-bar data (nothing reads them then)
NO_BALLBAR = (100.0, units.to_internal(0.5, "um"))
#: the eccentricity keys a run may give (each only where its pattern has the component)
COMPONENT_KEYS = ("ex_um", "ey_um", "ez_um")
#: the keys of a run's data: a planned run has none of them
DATA_KEYS = (*COMPONENT_KEYS, "trace_csv")
#: the keys only a planned run (``planned = true``) has
PLANNED_KEYS = (*PLANNED_RUN_KEYS, "length_mm")
#: a run's own geometry: the swivelled axis' arc, the held axes, the bar's side
GEOMETRY_KEYS = ("arc_deg", "step_deg", "hold_deg", "reversed")


class EngineKeys:
    """The engine's set-up and mount keys, read and written (a plug-in's ``ballbar_keys`` has the same members)."""

    keys: tuple[str, ...] = ()  # keys of [ballbar] besides the engine's
    setup_keys = ("R_B_mm",)
    mount_keys = ("position_mm",)
    run_geometry = True  # whether a run may give its own arc, held axes and bar side (GEOMETRY_KEYS)

    @staticmethod
    def read(r: TomlReader, t: dict, path: str) -> dict:
        """Fields of :class:`~mtmcal_bayes.campaign.Ballbar` its own keys give."""
        return {}

    @staticmethod
    def setup(r: TomlReader, sid: str, path: str, s: dict) -> Setup:
        return Setup(sid, r.number(s, "R_B_mm", path, positive=True), 0.0, 0.0)

    @staticmethod
    def check_setups(r: TomlReader, setups: dict[str, Setup], path: str) -> None:
        """Checks of the set-ups together beyond the engine's (distinct tool lengths)."""

    @staticmethod
    def mount(r: TomlReader, mid: str, path: str, m: dict) -> Mount:
        return Mount(mid, 0.0, 0.0, position=r.array(m, "position_mm", path, (3,)))

    @staticmethod
    def complete(ballbar: Ballbar, desc: MachineDescription) -> None:
        """The ball bar in the engine's terms: its runs read against the machine's chain."""
        ballbar.pattern_frames = functools.partial(chain_frame, desc)

    # the writing of the same keys (:mod:`.ballbar_writer`): what ``read``, ``setup`` and ``mount`` read back

    @staticmethod
    def write(ballbar: Ballbar) -> dict:
        """Its own keys of ``[ballbar]`` (beside the engine's) as written."""
        return {}

    @staticmethod
    def write_setup(s: Setup) -> dict:
        return {"R_B_mm": s.R_B}

    @staticmethod
    def write_mount(m: Mount) -> dict:
        return {"position_mm": [float(x) for x in m.position]}


@dataclasses.dataclass
class _Context:
    """What a run is read against: the machine's patterns, the ball bar read so far, the campaign's folder."""

    r: TomlReader
    desc: MachineDescription
    machine: Machine
    keys: object
    bb: Ballbar
    base_dir: Path | None

    def components(self, pattern: str) -> tuple[str, ...]:
        own = provided(self.machine, "pattern_components")
        return own(pattern) if own is not None else components(self.desc, pattern)


def read_ballbar(r: TomlReader, t: dict | None, machine: Machine, base_dir: Path | None) -> Ballbar:
    """``[ballbar]`` of a campaign on ``machine`` (absent: a probe-only campaign, no runs)."""
    P = "ballbar"
    desc = machine.description
    if t is None:
        return Ballbar(*NO_BALLBAR)
    keys = provided(machine, "ballbar_keys", EngineKeys)
    r.check_keys(t, {"instrument", "length_mm", "accuracy_um", "feed_mm_per_min", "convention", "alternative_reason",
                     "setups", "mounts", "runs", *keys.keys}, P)
    convention = read_campaign_convention(r, t, P, example=_convention_example(machine, desc))
    own = keys.read(r, t, P)
    length = r.number(t, "length_mm", P, positive=True)
    accuracy = units.to_internal(r.number(t, "accuracy_um", P, positive=True), "um")
    feed = r.number(t, "feed_mm_per_min", P, required=False, positive=True)
    setups = {sid: keys.setup(r, sid, path, s)
              for sid, path, s in r.subtables(t, "setups", P, allowed=set(keys.setup_keys), what="tool setup")}
    _distinct_tool_lengths(r, setups, P)
    keys.check_setups(r, setups, P)
    mounts = {mid: keys.mount(r, mid, path, m)
              for mid, path, m in r.subtables(t, "mounts", P, allowed=set(keys.mount_keys), what="W-ball mount")}
    bb = Ballbar(length, accuracy, r.string(t, "instrument", P), feed, setups, mounts, convention=convention, **own)
    keys.complete(bb, desc)

    raw = t.get("runs", [])  # absent: set-ups and mounts but nothing measured or planned yet
    if not isinstance(raw, list) or not all(isinstance(x, dict) for x in raw):
        r.fail(f"{P}.runs", "expected one or more [[ballbar.runs]] tables")
    ctx = _Context(r, desc, machine, keys, bb, base_dir)
    items = [_run(ctx, x, f"{P}.runs[{i}]") for i, x in enumerate(raw)]
    _distinct_runs(r, items, P, ctx)
    bb.runs = [x for x in items if isinstance(x, Run)]
    bb.planned = planned_in_order(r, [(i, x) for i, x in enumerate(items) if isinstance(x, PlannedRun)], P)
    for i, run in enumerate(items):
        try:
            check_run(run, bb) if isinstance(run, Run) else run_matrix(run, bb)
        except ConventionError as err:
            r.fail(f"{P}.runs[{i}].convention" if run.convention else f"{P}.convention", str(err))
    _reading_choice(r, t, items, bb)
    return bb


def _convention_example(machine: Machine, desc: MachineDescription) -> str:
    """A run's own convention as the message of an unknown one shows it: the first pattern's axis at 0° and 90°
    along its components (``"B0=+X,B90=+Z"`` on the thesis machine)."""
    patterns = provided(machine, "patterns") or [desc.rotary_axes[0].letter + "R"]
    own = provided(machine, "pattern_components")
    a, b = own(patterns[0]) if own is not None else components(desc, patterns[0])
    k = patterns[0][0]
    return f"{k}0=+{a[1].upper()},{k}90=+{b[1].upper()}"


def equal_setups(setups: dict[str, Setup], attribute: str) -> tuple[Setup, Setup] | None:
    """The first two set-ups (in the file's order) whose ``attribute`` is equal, else None."""
    items = list(setups.values())
    return next(((a, b) for i, a in enumerate(items) for b in items[i + 1:]
                 if getattr(a, attribute) == getattr(b, attribute)), None)


def _distinct_tool_lengths(r: TomlReader, setups: dict[str, Setup], path: str) -> None:
    """Two set-ups of one tool length: the second carries no information."""
    if pair := equal_setups(setups, "R_B"):
        a, b = pair
        r.fail(f"{path}.setups.{b.id}.R_B_mm", f"equal to {path}.setups.{a.id}.R_B_mm ({a.R_B:g} mm): a second tool "
               "length equal to the first carries no information")


def _pattern(ctx: _Context, t: dict, path: str) -> str:
    """The run's pattern: one of its machine's (a plug-in's own list, else every ``<axis><direction>``)."""
    r = ctx.r
    pattern = r.string(t, "pattern", path, required=True)
    known = provided(ctx.machine, "patterns")
    if known is not None and pattern not in known:
        r.fail(f"{path}.pattern", f"unknown pattern {pattern!r} (expected one of {' '.join(known)})")
    try:
        axis_of(ctx.desc, pattern)
    except ValueError as err:
        r.fail(f"{path}.pattern", str(err))
    return pattern


def _run(ctx: _Context, t: dict, path: str) -> Run | PlannedRun:
    r, bb = ctx.r, ctx.bb
    geometry = GEOMETRY_KEYS if ctx.keys.run_geometry else ()
    r.check_keys(t, {"pattern", "setup", "mount", "convention", "alternative_convention", "planned", *DATA_KEYS,
                     *PLANNED_KEYS, *geometry}, path)
    planned = t.get("planned", False)
    if not isinstance(planned, bool):
        r.fail(f"{path}.planned", f"expected true (a run planned but not yet measured) or false, got {kind_of(planned)}")
    if not planned:
        for key in PLANNED_KEYS:
            if key in t:
                r.fail(f"{path}.{key}", "only a planned run (planned = true) has this key; a measured run gives its "
                       "repeats as arrays (ex_um = [..., ...]) or trace_csv")
    pattern = _pattern(ctx, t, path)
    setup, mount = r.string(t, "setup", path, required=True), r.string(t, "mount", path, required=True)
    if setup not in bb.setups:
        r.fail(f"{path}.setup", f"names setup {setup!r}, which is not in [ballbar.setups] "
               f"(have: {', '.join(bb.setups)})")
    if mount not in bb.mounts:
        r.fail(f"{path}.mount", f"names mount {mount!r}, which is not in [ballbar.mounts] "
               f"(have: {', '.join(bb.mounts)})")
    conflict = provided(ctx.machine, "mount_conflict")
    if conflict is not None and (why := conflict(pattern, bb.mounts[mount])):
        r.fail(f"{path}.mount", why)
    ax = axis_of(ctx.desc, pattern)
    arc = _arc(r, t, path, ax) if ctx.keys.run_geometry else None
    hold = _hold(r, t, path, ctx.desc, swivelled=pattern[0])
    reversed_bar = t.get("reversed", False)
    if not isinstance(reversed_bar, bool):
        r.fail(f"{path}.reversed", f"expected true (the T ball on the other side of the W ball) or false, got "
               f"{kind_of(reversed_bar)}")
    convention = read_convention(r, t, path)
    if planned:
        if "alternative_convention" in t:
            r.fail(f"{path}.alternative_convention", "a planned run has no offsets to read another way; give it once "
                   "the run is measured")
        data = [k for k in DATA_KEYS if k in t]
        if data:
            r.fail(f"{path}.planned", f"planned = true but the run has data ({', '.join(data)}): once it is "
                   "measured, delete planned and repeats")
        run = planned_run(r, t, path, pattern=pattern, setup=setup, mount=mount)
        length = r.number(t, "length_mm", path, required=False, positive=True)
        run.length = None if length == bb.length else length
        run.arc_deg, run.hold_deg, run.convention, run.reversed = arc, hold, convention, reversed_bar
        return run
    run = Run(pattern, setup, mount, convention=convention,
              alternative_convention=read_convention(r, t, path, "alternative_convention"), arc_deg=arc,
              hold_deg=hold, reversed=reversed_bar)
    comps = ctx.components(pattern)
    for key in COMPONENT_KEYS:
        c = key[:2]
        if key not in t:
            continue
        if c not in comps:
            r.fail(f"{path}.{key}", f"pattern {pattern} has no component {c} (it gives {' and '.join(comps)})")
        v = units.to_internal(r.array(t, key, path, (None,)), "um")
        too_big = np.flatnonzero(np.abs(v) >= bb.length)
        if too_big.size:  # also keeps the models and the planner away from overflow
            i = int(too_big[0])
            r.fail(f"{path}.{key}[{i}]", f"{units.from_internal(v[i], 'um'):g} µm is not below the bar length "
                   f"L_B = {bb.length:g} mm: not an eccentricity")
        run.repeats[c] = v
    run.repeats = {c: run.repeats[c] for c in comps if c in run.repeats}  # in the pattern's order
    if "trace_csv" in t:
        if run.repeats:
            r.fail(f"{path}.trace_csv", "a run carries either eccentricity repeats or traces, not both")
        _traces(ctx, t, path, run)
    if not run.repeats:
        r.fail(path, f"no eccentricities: give {' and/or '.join(c + '_um' for c in comps)} or trace_csv")
    return run


def _traces(ctx: _Context, t: dict, path: str, run: Run) -> None:
    """``trace_csv``: one trace file per repeat, each fitted (:func:`~.traces.read_run_trace`) into ``run.repeats``."""
    r, comps = ctx.r, ctx.components(run.pattern)
    raw = t["trace_csv"]
    names = [raw] if isinstance(raw, str) else raw
    if not isinstance(names, list) or not names or not all(isinstance(x, str) and x for x in names):
        r.fail(f"{path}.trace_csv", "expected a file name or an array of file names")
    extracted = []
    run.trace_csv, run.trace_rms = names, []
    for name in names:
        fpath = (ctx.base_dir / name) if ctx.base_dir is not None else Path(name)
        if not fpath.exists():
            r.fail(f"{path}.trace_csv", f"trace file {str(fpath)!r} not found")
        if fpath.is_dir():
            r.fail(f"{path}.trace_csv", f"trace file {str(fpath)!r} is a directory")
        ex = read_run_trace(fpath, ctx.bb, ctx.desc, run, order=comps)
        extracted.append(ex.values)
        run.trace_rms.append(ex.rms)
    run.repeats = {c: np.array([e[c] for e in extracted]) for c in comps}


def _distinct_runs(r: TomlReader, runs: list[Run | PlannedRun], path: str, ctx: _Context) -> None:
    """Two runs of one measurement (pattern, setup, mount, arc, held axes, bar side) are refused
    (docs/campaign-format.md, "Duplicate runs"): merged they would pass two sessions, perhaps a re-clamped ball, for
    repeats of one measurement, whose repeat sd the likelihood takes as the run's repeatability.  Measured and planned
    runs alike (the file's order, ``runs`` indexing ``[[ballbar.runs]]``)."""
    first: dict[tuple, int] = {}
    for i, run in enumerate(runs):
        arc = ctx.bb.arc_of(run)
        key = (run.pattern, run.setup, run.mount, None if arc is None else tuple(np.round(arc, 9)),
               tuple(sorted((run.hold_deg or {}).items())), run.reversed)
        j = first.setdefault(key, i)
        if j == i:
            continue
        if isinstance(run, PlannedRun) or isinstance(runs[j], PlannedRun):
            where = "plan one run with all its repeats (repeats = N)"
            if isinstance(runs[j], Run):
                where = "a run already measured is not planned again on the same placement"
        else:
            arrays = ('trace_csv = ["a.csv", "b.csv"]' if run.trace_csv or runs[j].trace_csv
                      else f"{next(iter(run.repeats))}_um = [..., ...]")
            where = f"put all repeats of one measurement in one run's arrays ({arrays})"
        r.fail(f"{path}.runs[{i}]", f"repeats {path}.runs[{j}] (pattern {run.pattern}, setup {run.setup!r}, "
               f"mount {run.mount!r}): {where}; if the ball was re-clamped, give it its own [{path}.mounts.<id>]")


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


__all__ = ["NO_BALLBAR", "EngineKeys", "read_ballbar"]
