"""Machine minutes of a ball-bar campaign: what a calibration costs in downtime (SPEC §16, docs/design.md).

Items of the time model (minutes; ``--times FILE.toml`` or a campaign's ``[design.times]`` override each):

=====================  =======  ===================================================================
item                   default  what it covers, where the default comes from
=====================  =======  ===================================================================
mount_ballbar_min      15       first set-up of the ball bar on the machine: tool cup in the spindle,
                                centre cup on the table, centring the cups, setting the bar
                                (engineering estimate from ballbar practice: a QC20-W type test
                                is commonly quoted as "set up and measure in 15 minutes")
tool_change_min        10       change the tool length with an extension bar (thesis Step 5, Table
                                4.3), measure it, re-centre the T ball on the W ball (estimate)
reclamp_w_ball_min     10       clamp the W ball at a new placement (radius R_C, height Z_C, or a
                                fresh placement of the same one) and re-centre (estimate)
pattern_change_min     3        next pattern at the same set-up and placement: re-seat the bar,
                                load the program (estimate)
dwell_min              0.5      per run: approach, run-in/run-out arcs, start and stop of the data
                                capture (estimate; ISO 230-4 test practice adds arcs of overshoot)
feed_mm_per_min        —        the ball-bar feed; default the campaign's ``[ballbar]
                                feed_mm_per_min`` (1000 in the thesis campaign), else 1000
rotary_deg_per_min     360      the slowest a pattern's rotary axis turns: one C turn a minute
                                (estimate), which bounds a run whose relative path is short (CR
                                with R_C = L_B: the T ball on the C axis, the table turning under it)
directions             2        each run measured clockwise and counter-clockwise (ISO 230-4)
index_rotary_min       0.5      a described machine's run with other rotary axes held off 0: index
                                them to the held position and clamp before the arc (estimate)
mount_rtest_min        15       an R-test session's set-up: the sphere on the table, the nest in the
                                spindle, the nest centred on the sphere and the sensors zeroed (estimate;
                                the commercial devices quote a set-up of 10-20 minutes)
index_rtest_min        0.25     per R-test position: index the rotary axes (the linear axes follow,
                                keeping the nest on the sphere) and clamp (estimate)
dwell_rtest_min        0.0333   per R-test position: the dwell while the sensors read (the 2000 ms of
                                ``ncgen --rtest``'s default ``G04 P2000``)
mount_probe_min        10       a touch-probe session's set-up: the probe in the spindle, the sphere on
                                the table, the stylus qualified (estimate)
probe_position_min     0.5      per probe position and repeat: index the rotary axes, probe the sphere
                                (five points) and retract (estimate; the controller cycles take 20-40 s)
instrument_change_min  5        a design's change from one instrument to the next (ball bar, probe,
                                R-test): take the one off the machine and clear the table before the
                                next one's set-up (estimate)
stylus_change_min      5        a probe run with another stylus, or a stylus set anew: change it and
                                qualify it on the sphere (estimate)
move_sphere_min        5        a probe run with the sphere elsewhere, or placed anew: unclamp, move,
                                clamp it (estimate)
=====================  =======  ===================================================================

An R-test run (:func:`rtest_run_minutes`) takes ``repeats × positions × (index_rtest_min + dwell_rtest_min)``
indexed, or ``repeats × span / rotary_deg_per_min`` swept (the positions logged on the move), plus
``mount_rtest_min`` for the nest's set-up when the session has none yet; a touch-probe run
(:func:`probe_run_minutes`) ``repeats × positions × probe_position_min``, plus ``mount_probe_min``.

The measuring motion of a run takes ``repeats × directions × max(path / feed, span / rotary)``, plus
``index_rotary_min`` when it holds another rotary axis off 0: ``path`` is the length of the linear-axis commands
(X, Y, Z) of the engine's pattern (:func:`mtmcal_bayes.machines.patterns.pattern_commands`) over the grid of the
run's :class:`Motion`, ``span`` that grid's range in degrees.  One :class:`MachineClock` times every machine; the
motion a run is timed over is what the machine's planning kit gives: the engine's, a designed run over its own arc
(:mod:`mtmcal_bayes.planning.chain_clock`); a plug-in's, e.g. the thesis' patterns over their whole range, densely,
the path the feed word of their measuring programs is programmed along (:mod:`mtmcal_bayes.plugins.thesis.timing`).

A schedule measures the runs in the given order from a start state (ball bar mounted or not, the
current set-up and placement): a run at another set-up than the previous costs a tool change (the
first set-up too), at another placement a re-clamp, at the same set-up and placement a pattern
change; the first run needs the bar mounted.  :func:`canonical_order` groups the runs by set-up,
then by placement, so that each change happens once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

import numpy as np

from .machines.patterns import pattern_commands

#: default ball-bar feed when neither the time model nor the campaign gives one, mm/min
DEFAULT_FEED = 1000.0
#: a single step longer than one shift is a unit slip, not a time
MAX_STEP_MIN = 480.0
#: feeds beyond this are not ball-bar feeds (mm/min)
MAX_FEED = 50_000.0
#: rotary speeds outside these bounds are unit slips (°/min): a turn in 6 h, or 100 rev/min
MIN_ROTARY, MAX_ROTARY = 1.0, 36_000.0


@dataclass(frozen=True)
class TimeModel:
    """The machine-time model (minutes; see the module docstring for each item and its default)."""

    mount_ballbar_min: float = 15.0
    tool_change_min: float = 10.0
    reclamp_w_ball_min: float = 10.0
    pattern_change_min: float = 3.0
    dwell_min: float = 0.5
    feed_mm_per_min: float | None = None
    rotary_deg_per_min: float = 360.0
    directions: int = 2
    index_rotary_min: float = 0.5
    mount_rtest_min: float = 15.0
    index_rtest_min: float = 0.25
    dwell_rtest_min: float = 2.0 / 60.0
    mount_probe_min: float = 10.0
    probe_position_min: float = 0.5
    instrument_change_min: float = 5.0
    stylus_change_min: float = 5.0
    move_sphere_min: float = 5.0

    def __post_init__(self):
        for key, value, why in self.problems():
            raise ValueError(f"{key}: {why}")

    def problems(self) -> list[tuple[str, object, str]]:
        """``(key, value, reason)`` of every value outside its bounds (empty when all are valid)."""
        out = []
        for f in fields(self):
            v = getattr(self, f.name)
            if f.name == "feed_mm_per_min" and v is None:
                continue
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                out.append((f.name, v, f"expected a finite number, got {v!r}"))
            elif f.name == "directions":
                if v not in (1, 2):
                    out.append((f.name, v, f"1 or 2 (one direction, or clockwise and counter-clockwise), got {v!r}"))
            elif f.name == "feed_mm_per_min":
                if not 0 < v <= MAX_FEED:
                    out.append((f.name, v, f"a feed above 0 and at most {MAX_FEED:g} mm/min, got {v:g}"))
            elif f.name == "rotary_deg_per_min":
                if not MIN_ROTARY <= v <= MAX_ROTARY:
                    out.append((f.name, v, f"a rotary speed from {MIN_ROTARY:g} to {MAX_ROTARY:g} °/min, got {v:g}"))
            elif v < 0:
                out.append((f.name, v, f"a time cannot be negative, got {v:g} min"))
            elif v > MAX_STEP_MIN:
                out.append((f.name, v, f"{v:g} min is longer than a shift ({MAX_STEP_MIN:g} min): hours or seconds "
                            "written for minutes?"))
        return out

    def feed(self, campaign_feed: float | None) -> float:
        return self.feed_mm_per_min or campaign_feed or DEFAULT_FEED


TIME_KEYS = tuple(f.name for f in fields(TimeModel))


@dataclass(frozen=True)
class Motion:
    """What one run makes the axes do, as the clock times it: ``pattern`` over ``arc_deg`` (k,) degrees, tool length
    ``length`` and bar ``bar`` (mm), the W ball at ``ball`` (3,) mm (home pose), the other rotary axes at
    ``hold_deg`` ((letter, degrees), ...), the bar on the other side if ``reverse``
    (:func:`~mtmcal_bayes.machines.patterns.pattern_commands`).  Tuples throughout: a motion is its own cache key."""

    pattern: str
    length: float
    ball: tuple[float, float, float]
    bar: float
    arc_deg: tuple[float, ...]
    hold_deg: tuple[tuple[str, float], ...] = ()
    reverse: bool = False


def path_length(desc, motion: Motion) -> float:
    """Length of the linear-axis commands (X, Y, Z) of ``motion`` on the machine ``desc``, mm: the polygon through
    its grid's points."""
    cmd = pattern_commands(desc, motion.pattern, length=motion.length, ball=np.array(motion.ball), bar=motion.bar,
                           arc_deg=np.array(motion.arc_deg), hold_deg=dict(motion.hold_deg) or None,
                           reverse=motion.reverse)
    xyz = np.stack([cmd.q[a] for a in "XYZ"], axis=-1)
    return float(np.sum(np.linalg.norm(np.diff(xyz, axis=0), axis=1)))


@dataclass(frozen=True)
class Event:
    """One step of a schedule: ``kind`` ("mount ball bar", "tool change", "re-clamp W ball", "pattern change",
    "measure"), the run it belongs to (index into the ordered runs), when it starts and how long it takes, min."""

    kind: str
    run_index: int | None
    start_min: float
    minutes: float
    label: str = ""


@dataclass
class Schedule:
    events: list[Event] = field(default_factory=list)

    @property
    def total_min(self) -> float:
        return float(sum(e.minutes for e in self.events))

    def run_total_min(self, n_runs: int) -> list[float]:
        """Per run: its measuring plus the set-up changes it causes, min."""
        out = [0.0] * n_runs
        for e in self.events:
            if e.run_index is not None:
                out[e.run_index] += e.minutes
        return out


class MachineClock:
    """The time model applied to runs on the machine ``desc`` (module docstring); ``motion(run) ->`` :class:`Motion`
    what a run makes the axes do, ``feed`` the campaign's feed (mm/min; the time model's wins).

    A run is any object with ``pattern``, ``setup`` and ``mount`` ids (or ``Setup``/``Mount`` objects) and
    ``repeats`` (and whatever ``motion`` reads).  ``start`` = (ball bar mounted, current setup id, current mount id).
    """

    def __init__(self, model: TimeModel, desc, motion, *, feed: float | None = None):
        self.model, self.desc, self.motion = model, desc, motion
        self.feed_mm_per_min = model.feed(feed)
        self._one: dict[Motion, tuple[float, float]] = {}

    def one_direction(self, motion: Motion) -> tuple[float, float]:
        """``(minutes of one direction of the measuring motion, minutes of indexing before it)``."""
        if motion not in self._one:
            m = self.model
            span = float(motion.arc_deg[-1] - motion.arc_deg[0])
            one = max(path_length(self.desc, motion) / self.feed_mm_per_min, span / m.rotary_deg_per_min)
            index = m.index_rotary_min if any(v != 0 for _, v in motion.hold_deg) else 0.0
            self._one[motion] = one, index
        return self._one[motion]

    def run_minutes(self, run) -> float:
        """Dwell, indexing and the measuring motion of one run of a schedule, min."""
        one, index = self.one_direction(self.motion(run))
        return self.model.dwell_min + index + run.repeats * self.model.directions * one

    def _steps(self, runs, start):
        """``(run index, kind, minutes)`` of every step of ``runs`` measured in the given order from ``start``."""
        mounted, setup, mount = start
        m = self.model
        for i, r in enumerate(runs):
            sid, mid = _id(r.setup), _id(r.mount)
            if not mounted:
                yield i, "mount ball bar", m.mount_ballbar_min
            if sid != setup:
                yield i, "tool change", m.tool_change_min
            if mid != mount:
                yield i, "re-clamp W ball", m.reclamp_w_ball_min
            if mounted and sid == setup and mid == mount:
                yield i, "pattern change", m.pattern_change_min
            yield i, "measure", self.run_minutes(r)
            mounted, setup, mount = True, sid, mid

    def schedule(self, runs, start=(False, None, None)) -> Schedule:
        """The runs measured in the given order from ``start`` (module docstring)."""
        t, events = 0.0, []
        for i, kind, minutes in self._steps(runs, start):
            r = runs[i]
            events.append(Event(kind, i, t, minutes, f"{r.pattern}@{_id(r.setup)}/{_id(r.mount)}"))
            t += minutes
        return Schedule(events)

    def total(self, runs, start=(False, None, None)) -> float:
        """:meth:`schedule`'s total minutes without its events (the same sum, in the same order)."""
        t = 0.0
        for _, _, minutes in self._steps(runs, start):
            t += minutes
        return t


def rtest_run_minutes(model: TimeModel, positions: int, repeats: int = 1, *, sweep_span_deg: float | None = None,
                      set_up: bool = True) -> float:
    """Machine minutes of one R-test run of ``positions`` positions read ``repeats`` times: indexed (each position
    ``index_rtest_min + dwell_rtest_min``) or, with ``sweep_span_deg``, swept over that span at
    ``rotary_deg_per_min`` with its positions logged on the move; plus the nest's set-up ``mount_rtest_min`` where
    ``set_up`` (a session without one yet)."""
    each = sweep_span_deg / model.rotary_deg_per_min if sweep_span_deg is not None else \
        positions * (model.index_rtest_min + model.dwell_rtest_min)
    return (model.mount_rtest_min if set_up else 0.0) + repeats * each


def probe_run_minutes(model: TimeModel, positions: int, repeats: int = 1, *, set_up: bool = True) -> float:
    """Machine minutes of one touch-probe run of ``positions`` positions probed ``repeats`` times each
    (``probe_position_min``), plus the probe's set-up ``mount_probe_min`` where ``set_up``."""
    return (model.mount_probe_min if set_up else 0.0) + repeats * positions * model.probe_position_min


def _id(x) -> str:
    return x if isinstance(x, str) else x.id


def canonical_order(runs, start_setup: str | None = None, start_mount: str | None = None) -> list[int]:
    """Indices of ``runs`` grouped by set-up (the current one first, then in order of first appearance), within a
    set-up by placement (the current one first), in the given order within a group."""
    setups = list(dict.fromkeys(_id(r.setup) for r in runs))
    if start_setup in setups:
        setups.remove(start_setup)
        setups.insert(0, start_setup)
    out = []
    for s in setups:
        idx = [i for i, r in enumerate(runs) if _id(r.setup) == s]
        mounts = list(dict.fromkeys(_id(runs[i].mount) for i in idx))
        if s == start_setup and start_mount in mounts:
            mounts.remove(start_mount)
            mounts.insert(0, start_mount)
        for mt in mounts:
            out += [i for i in idx if _id(runs[i].mount) == mt]
    return out


__all__ = ["TimeModel", "TIME_KEYS", "Motion", "MachineClock", "Schedule", "Event", "canonical_order", "path_length",
           "rtest_run_minutes", "probe_run_minutes",
           "DEFAULT_FEED", "MAX_STEP_MIN", "MAX_FEED"]
