"""Measuring NC programs of every machine (``ncgen``, ``design``; SPEC §19, §20): one ball-bar run, one touch-probe run.

One path for every machine: :func:`campaign_program` selects what to program (a pattern at a set-up and mount, the
campaign's N-th ball-bar run, measured or planned, or a probe run of a probe that has ``[[probe.runs]]``), checks it
(the pattern against the description, set-up and mount, the arc and the held axes against their travels) and
computes its commands through the machine's chain (:class:`BallbarProgram`); the machine's **program format** writes
them.  A format is the engine's own (:data:`CHAIN_FORMAT`, below) unless a plug-in provides ``program_format`` (the
thesis': Fig 4.30(a)'s blocks in its NC frame).  A format states the options of its own it honours (``options``:
the thesis' ``R_B_mm``, ``start``, ``n``), its default step, whether a program without a feed takes the campaign's,
its grid of angles and its tool length; an option no format of the machine honours is refused by name.

Both programs are functions of the campaign's geometry only (setups, mounts, bar length, styli, spheres, the
description), so a designed campaign's planned runs get programs before anything is measured.

**Ball bar** (:func:`ballbar_program`).  A run ``<K><d>`` swivels rotary axis K over its arc while the linear
axes keep the tool ball at the bar length from the W ball along the pattern's direction d, the other rotary axes
held.  The commanded positions of every point are those of
:func:`mtmcal_bayes.machines.patterns.pattern_commands` — the very commands the ``chain`` and ``linear`` models
predict the run with — so measuring with the program gives what the model predicts; the W ball where the machine's
plug-in places a run of its campaign format (``run_placement``: the thesis' B patterns on the C axis), else at its
mount's position.  The engine's format: the rotary axes to the start pose (held axes and K at its first angle) with
the tool backed off along its axis, the start point, a stop to mount the bar, one ``G01`` block per point of the
arc with every axis word, a stop, the tool backed off again.  Between two blocks the control moves each axis
linearly, so the bar length is exact at the blocks (the points the model reads) and off by a chord error between
them; the header states it.

**Touch probe** (:func:`probe_program`).  A run probes one sphere at indexed positions of the rotary axes.  At
each position: the rotary axes indexed (a block with rotary words only, the stylus clear), then five probing
moves onto the sphere — along the stylus axis onto its pole and from four directions square to the stylus
(its equator) — each a ``G00`` approach to ``contact + clearance`` from the sphere centre and a ``G31`` skip move
to ``contact − overtravel``.  The sphere centre fitted to the five trigger positions is the run's reading
(``centres_mm``).  ``G31`` and recording its trigger position are Fanuc-type; other controls probe with their
own move or cycle (the header says so).

Commands are the description's: X, Y, Z in mm and the rotary axes in degrees, absolute, every axis 0 at the home
pose (docs/machines.md, Conventions).  Words in ISO order, ``X Y Z`` then the rotary letters
(:func:`~mtmcal_bayes.io.nc_axes.axis_letters`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from numbers import Real

import numpy as np

from ..campaign import Run, Setup
from ..errors import InputError, ParameterError
from ..machines.description import FRAME, Axis, MachineDescription
from ..machines.patterns import (PatternCommands, axis_of, default_arc_deg, pattern_commands,
                                 placement_commands, tool_home)
from ..machines.plugins import provided
from ..units import fixed
from .machine_reader import description_of
from .nc_axes import DECIMALS, axis_block, axis_letters, comment
from .program_parts import (RETRACT_MM, _deg, _linear_notes, _name, _positive, _rotary_travel, _shift, measured_run,
                            _tool_direction, _words, relative_position)
from .rtest_program import rtest_program, rtest_run

#: probing: centre distance of stylus ball and sphere at contact (sphere radius + stylus-ball radius), mm —
#: e.g. a 25 mm sphere and a 5 mm stylus ball; give the real one
TOUCH_RADIUS_MM = 15.0
#: probing: the approach stops this far before contact, and the skip move aims this far past it, mm
CLEARANCE_MM, OVERTRAVEL_MM = 5.0, 2.0
#: probing feed of the skip moves, mm/min (the thesis' Fig 5.12: F100)
PROBE_FEED = 100.0
#: the chord error between blocks the header suggests a finer step for, mm
CHORD_MM = 0.001
#: the step of a pattern's program over an arc given as its two ends, where the format states no step, degrees
ARC_STEP_DEG = 1.0
#: what the bar direction of each pattern letter is, said in a header
_DIRECTION = {"R": "radial from the {K} line", "T": "tangential about the {K} line", "A": "along the {K} axis",
              "X": "along the machine X axis", "Y": "along the machine Y axis", "Z": "along the machine Z axis"}
_COMMANDS_NOTE = ("axis words: the description's commands, mm and deg, absolute, every axis 0 at the home pose; "
                  "run in the coordinate system in which these are the axis positions")


# --------------------------------------------------------------------------- ball bar: what the engine computes
@dataclass(frozen=True)
class BallbarProgram:
    """One ball-bar program as the engine selected, checked and computed it, for a format to write.

    ``run`` the run (measured, planned, or of a pattern), ``axis`` the rotary axis it swivels, ``setup`` and
    ``mount`` the campaign's; ``length`` the tool length the commands are for, mm (the set-up's unless the format
    takes another), ``ball`` the W ball (3,) mm at the home pose, ``bar`` mm; ``arc`` (k,) degrees of the swivelled
    axis, ``held`` {letter: degrees} of the rotary axes held, ``reverse`` the T ball on the other side of the W ball
    from the engine's pattern; ``commands`` the nominal commands (mm, rad) of every
    point; ``feed`` mm/min of the arc blocks or None."""

    campaign: object
    desc: MachineDescription
    run: object
    axis: Axis
    setup: Setup
    mount: object
    length: float
    ball: np.ndarray
    bar: float
    arc: np.ndarray
    held: dict = field(default_factory=dict)
    reverse: bool = False
    commands: PatternCommands | None = None
    feed: float | None = None


class ChainFormat:
    """The engine's program format: the description's commands with a header of notes, the start pose, stops to
    mount and remove the bar, one block per point (see the module docstring); no options of its own."""

    name = "the description's commands"
    #: options of its own beyond the engine's (ncgen's keyword names)
    options: tuple[str, ...] = ()
    #: the step of its ball-bar programs where none is asked, degrees (None: the run's own arc)
    step_deg: float | None = None
    #: whether a program without a feed takes the campaign's ``feed_mm_per_min``
    campaign_feed = True

    def alone(self, campaign, options: dict):
        """The campaign of a program asked without one: ``campaign`` (the built-in one), the engine's has no other."""
        return campaign

    def grid(self, arc: np.ndarray, step_deg: float | None, options: dict) -> np.ndarray:
        """The angles (degrees) of a program over ``arc``: the arc itself, or from its first to its last angle by
        ``step_deg``."""
        if step_deg is None:
            return arc
        _positive("step_deg", step_deg)
        grid = np.arange(arc[0], arc[-1] + 1e-9, step_deg)
        if len(grid) < 9:
            raise ParameterError("step_deg", f"{step_deg:g} deg gives fewer than 9 angles over [{arc[0]:g}, "
                                 f"{arc[-1]:g}] deg: too few to read the eccentricities from")
        return grid

    def tool_length(self, setup, options: dict) -> float:
        """The tool length of a program at ``setup``, mm: the set-up's."""
        return setup.R_B

    def ballbar(self, program: BallbarProgram, options: dict, *, decimals: int = DECIMALS) -> str:
        """The program's text: header, start pose, the arc's blocks, back off (the module docstring)."""
        return _chain_ballbar(program, decimals)


#: the engine's program format (:class:`ChainFormat`)
CHAIN_FORMAT = ChainFormat()


def program_format(machine):
    """The program format of ``machine``: its plug-in's (``program_format``), else the engine's."""
    return provided(machine, "program_format", CHAIN_FORMAT)


def _checked_run(campaign, run, *, step_deg, fmt, options: dict) -> BallbarProgram:
    """The :class:`BallbarProgram` of ``run`` (no commands yet), each part checked (ParameterError): its arc the
    format's grid (``fmt.grid``) at ``step_deg``, its tool length the format's."""
    desc = description_of(campaign.machine)
    try:
        ax = axis_of(desc, run.pattern)
    except ValueError as err:
        raise ParameterError("pattern", str(err)) from None
    bb = campaign.ballbar
    for name, value, have in (("setup", run.setup, bb.setups), ("mount", run.mount, bb.mounts)):
        if value not in have:
            raise ParameterError(name, f"no {name} {value!r} in the campaign (have: {', '.join(have) or 'none'})")
    own = bb.arc_of(run)
    arc = fmt.grid(default_arc_deg(ax) if own is None else np.asarray(own, dtype=float), step_deg, options)
    _rotary_travel(ax, arc, "arc_deg")
    held = {}
    for letter, value in (run.hold_deg or {}).items():
        other = desc.axes.get(letter)
        if other is None or not other.rotary or letter == ax.letter:
            others = [a.letter for a in desc.rotary_axes if a.letter != ax.letter]
            raise ParameterError("hold_deg", f"{letter} is not a held rotary axis of {run.pattern} (expected one of "
                                 f"{', '.join(others) or 'none'})")
        if isinstance(value, bool) or not isinstance(value, Real) or not np.isfinite(value):
            raise ParameterError("hold_deg", f"{letter} = {value!r}: not a number of degrees")
        _rotary_travel(other, value, "hold_deg")
        held[letter] = float(value)
    setup, mount = bb.setups[run.setup], bb.mounts[run.mount]
    ball, reverse = _placement(campaign, run, mount)
    return BallbarProgram(campaign, desc, run, ax, setup, mount, fmt.tool_length(setup, options), ball,
                          getattr(run, "length", None) or bb.length, arc, held, reverse)


def _placement(campaign, run, mount) -> tuple[np.ndarray, bool]:
    """``(W ball (3,) mm at the home pose, bar reversed)`` of ``run`` on ``mount``: where the machine's plug-in places
    a run of its campaign format (``run_placement``: the thesis' B patterns with the W ball on the C axis, its BT and
    CR bar sides), else at the mount's position with the campaign's bar side."""
    place = provided(campaign.machine, "run_placement")
    if place is None:
        return mount.centre(), campaign.ballbar.bar_reversed(run)
    ball, _, reverse = place(campaign, run.pattern, mount)
    return ball, reverse != run.reversed


def _with_commands(program: BallbarProgram) -> BallbarProgram:
    """``program`` with its nominal commands (``pattern_commands`` at its tool length, W ball, bar, arc, holds)."""
    run = program.run
    try:
        cmd = pattern_commands(program.desc, run.pattern, length=program.length, ball=program.ball, bar=program.bar,
                               arc_deg=program.arc, hold_deg=program.held, reverse=program.reverse)
    except ValueError as err:  # a pattern the description does not have
        raise ParameterError("pattern", str(err)) from None
    return dataclasses.replace(program, commands=cmd)


def ballbar_program(campaign, run, *, feed: float | None = None, step_deg: float | None = None,
                    decimals: int = DECIMALS, options: dict | None = None) -> str:
    """The measuring program of ball-bar ``run`` (a :class:`~mtmcal_bayes.campaign.Run` or
    :class:`~mtmcal_bayes.campaign.PlannedRun`: pattern, setup, mount, ``arc_deg`` (None: its campaign format's or
    the axis' grid), ``hold_deg``) of ``campaign``, as text in its machine's program format (:func:`program_format`).
    ``feed`` mm/min on the arc blocks (default: the campaign's ``feed_mm_per_min`` where the format takes it, else
    none); ``step_deg`` re-grids the run's arc (default the format's step); ``decimals`` of every axis word;
    ``options`` the format's own {name: value}."""
    fmt = program_format(campaign.machine)
    options = options or {}
    program = _checked_run(campaign, run, step_deg=fmt.step_deg if step_deg is None else step_deg, fmt=fmt,
                           options=options)
    if feed is None and fmt.campaign_feed:
        feed = campaign.ballbar.feed_mm_per_min
    if feed is not None:
        _positive("feed", feed)
    program = _with_commands(dataclasses.replace(program, feed=feed))
    return fmt.ballbar(program, options, decimals=decimals)


def _chain_ballbar(program: BallbarProgram, decimals: int) -> str:
    """The engine's format of a ball-bar program (:class:`ChainFormat`)."""
    desc, run, ax, arc, held, feed = program.desc, program.run, program.axis, program.arc, program.held, program.feed
    letters = axis_letters(desc)
    q, k = program.commands.q, len(arc)
    tool = tool_home(desc, program.length)
    s = _tool_direction(desc, {a.letter: q[a.letter][[0, -1]] for a in desc.rotary_axes})
    backed = [_shift(q, i, -RETRACT_MM * s[j]) for j, i in enumerate((0, k - 1))]
    mid = {a: 0.5 * (v[:-1] + v[1:]) for a, v in q.items()}
    chord = np.abs(np.linalg.norm(relative_position(desc, mid, tool=tool, ball=program.ball), axis=1) - program.bar)
    fine = (arc[1] - arc[0]) * np.sqrt(CHORD_MM / chord.max()) if k > 1 and chord.max() > 0 else None
    place = placement_commands(desc, length=program.length, ball=program.ball)
    every = {a: np.concatenate([np.atleast_1d(p[a]) for p in (q, *backed)]) for a in q}
    held_text = ", ".join(f"{a} {held.get(a, 0.0):g} deg" for a in sorted(held.keys() | {
        b.letter for b in desc.rotary_axes if b.letter != ax.letter})) or "none"
    step = f" by {arc[1] - arc[0]:g} deg" if k > 1 and np.allclose(np.diff(arc), arc[1] - arc[0]) else ""
    header = [
        f"mtmcal-bayes measuring program: ball-bar run {run.pattern} of {_name(program.campaign)}",
        f"machine: {desc.name or 'described machine'}, {desc.configuration}",
        f"pattern {run.pattern}: {ax.letter} from {arc[0]:g} to {arc[-1]:g} deg{step}, {k} points; bar "
        + _DIRECTION[run.pattern[1]].format(K=ax.letter) + f"; held: {held_text}",
        f"setup {run.setup}: tool length R_B {program.length:g} mm from the spindle point; mount {run.mount}: W ball "
        "at " + " ".join(f"{a}{v:g}" for a, v in zip(FRAME, program.ball)) + " mm at the home pose",
        f"bar {program.bar:g} mm; before this program the W ball is set where the dummy sphere in the spindle sits at "
        + axis_block(_words(letters, place, 0), motion="", decimals=decimals).strip(),
        _COMMANDS_NOTE,
        f"bar length exact at the blocks; between them each axis moves linearly: up to {chord.max():.4f} mm off"
        + (f" - steps of {fine:.2g} deg keep it under {CHORD_MM:g} mm" if chord.max() > CHORD_MM and step else ""),
        *_linear_notes(desc, every),
        f"feed F{feed:g} on the arc blocks: the control's feed of a rotary-and-linear move" if feed is not None else
        "no feed word: give one before running",
    ]
    lines = [comment(h) for h in header]
    lines += ["G90 G21", comment("rotary axes to the start pose, the tool backed off along its axis"),
              axis_block(_words(letters, backed[0], 0), motion="G00", decimals=decimals),
              axis_block(_words(letters, q, 0), motion="G00", decimals=decimals, note="start point"),
              "M00 " + comment("mount the ball bar, start recording"),
              comment(f"the arc: {k} points")]
    lines += [axis_block(_words(letters, q, i), feed=feed, decimals=decimals) for i in range(k)]
    lines += ["M00 " + comment("stop recording, remove the ball bar"),
              axis_block(_words(letters, backed[1], 0), motion="G00", decimals=decimals, note="back off"), "M30"]
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- touch probe
def probe_centres(campaign, probe_run) -> tuple[dict, np.ndarray, np.ndarray]:
    """``(q_rot {letter: (a,)} rad, centres (a, 3) mm, stylus directions (a, 3))`` of ``probe_run``'s positions:
    the nominal commanded X, Y, Z at which the stylus-ball centre is at the sphere centre (the model's nominal
    reading), and the stylus' direction, machine frame."""
    desc = description_of(campaign.machine)
    probe = campaign.probe
    if probe_run.stylus not in probe.styli and (gap := campaign.probe_gap()) is not None:
        raise gap.error(campaign.source)
    if probe_run.stylus not in probe.styli:
        raise ParameterError("probe", f"run {probe_run.id!r}: no stylus {probe_run.stylus!r} in the campaign")
    lengths = {a: len(v) for a, v in probe_run.angles.items()}
    if len(set(lengths.values())) > 1:
        raise ParameterError("probe", f"run {probe_run.id!r}: its axes have different numbers of positions "
                             f"({', '.join(f'{a} {n}' for a, n in lengths.items())})")
    n = next(iter(lengths.values()), probe_run.centres.shape[1])
    q_rot = {}
    for ax in desc.rotary_axes:
        q_rot[ax.letter] = np.asarray(probe_run.angles.get(ax.letter, np.zeros(n)), dtype=float)
        _rotary_travel(ax, _deg(q_rot[ax.letter]), "probe")
    for letter in probe_run.angles:
        if letter not in q_rot:
            raise ParameterError("probe", f"run {probe_run.id!r}: {letter} is not a rotary axis of this machine")
    tool = tool_home(desc, probe.centre_length(probe_run.stylus))
    zero = {a: np.zeros(n) for a in FRAME}
    centres = -relative_position(desc, {**q_rot, **zero}, tool=tool, ball=np.asarray(probe_run.sphere, float))
    return q_rot, centres, _tool_direction(desc, q_rot)


def probe_directions(s: np.ndarray) -> np.ndarray:
    """The five probing directions ``(5, 3)`` at stylus direction ``s`` (3,): from the sphere centre to the
    stylus centre at contact — the pole (against the stylus, −s), then four square to it."""
    ref = np.eye(3)[int(np.argmin(np.abs(s)))]
    e1 = np.cross(s, ref)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(s, e1)
    return np.array([-s, e1, e2, -e1, -e2])


def probe_program(campaign, probe_run, *, touch_radius_mm: float = TOUCH_RADIUS_MM,
                  clearance_mm: float = CLEARANCE_MM, overtravel_mm: float = OVERTRAVEL_MM, feed: float = PROBE_FEED,
                  decimals: int = DECIMALS) -> str:
    """The NC program of touch-probe run ``probe_run`` (a :class:`~mtmcal_bayes.campaign.ProbeRun`: indexed
    positions, sphere, stylus) of ``campaign``, as text in the engine's format (see the module docstring).
    ``touch_radius_mm``: sphere radius plus stylus-ball radius; ``clearance_mm`` before contact,
    ``overtravel_mm`` past it; ``feed`` of the skip moves, mm/min."""
    desc = description_of(campaign.machine)
    for name, v in (("touch_radius_mm", touch_radius_mm), ("clearance_mm", clearance_mm),
                    ("overtravel_mm", overtravel_mm), ("feed", feed)):
        if not (np.isfinite(v) and v > 0):
            raise ParameterError(name, f"must be a positive number, got {v}")
    if overtravel_mm >= touch_radius_mm:
        raise ParameterError("overtravel_mm", f"{overtravel_mm:g} mm reaches the sphere centre's side of the "
                             f"touch radius {touch_radius_mm:g} mm")
    q_rot, centres, s = probe_centres(campaign, probe_run)
    letters = axis_letters(desc)
    rotary = [a for a in letters if a not in FRAME]
    n = len(centres)
    near, far = touch_radius_mm + clearance_mm, touch_radius_mm + RETRACT_MM

    def at(i, point, **kw):
        pose = dict(zip(FRAME, point), **{a: float(_deg(q_rot[a][i])) for a in rotary})
        return axis_block({a: pose[a] for a in letters}, decimals=decimals, **kw)

    header = [
        f"mtmcal-bayes measuring program: touch-probe run {probe_run.id} of {_name(campaign)}",
        f"machine: {desc.name or 'described machine'}, {desc.configuration}",
        f"stylus {probe_run.stylus}: length {campaign.probe.centre_length(probe_run.stylus):g} mm from the spindle "
        "point; "
        "sphere at " + " ".join(f"{a}{v:g}" for a, v in zip(FRAME, probe_run.sphere)) + " mm at the home pose; "
        f"{n} positions of " + " ".join(rotary),
        _COMMANDS_NOTE,
        f"per position: index, then 5 probing moves - the pole along the stylus and 4 square to it; approach to "
        f"{near:g} mm from the sphere centre, G31 to {touch_radius_mm - overtravel_mm:g} mm; touch radius "
        f"{touch_radius_mm:g} mm = sphere radius + stylus-ball radius, set it for your sphere and stylus",
        "G31 is the skip move of Fanuc-type controls, the trigger position read from the control; elsewhere use the "
        "control's probing move or run its sphere cycle at the sphere-centre position of each position",
        "reading of a position: the sphere centre fitted to its 5 trigger positions, the stylus-ball centre's "
        "commanded X Y Z - the run's centres_mm",
        "start with the stylus clear of the workpiece: the rotary axes index without a linear move",
    ]
    lines = [comment(h) for h in header] + ["G90 G21"]
    for i in range(n):
        c, d = centres[i], probe_directions(s[i])
        where = " ".join(f"{a}{_deg(q_rot[a][i]):g}" for a in rotary)
        lines.append(comment(f"position {i + 1} of {n}: {where}; sphere centre at "
                             + " ".join(f"{a}{fixed(v, decimals)}" for a, v in zip(FRAME, c))))
        lines.append(axis_block({a: float(_deg(q_rot[a][i])) for a in rotary}, motion="G00", decimals=decimals,
                                note="index"))
        lines.append(at(i, c - far * s[i], motion="G00"))
        for j, u in enumerate(d):
            over = c + near * u - (near * s[i] if j else 0.0)  # the equator's approaches come down from above
            if j:
                lines.append(at(i, over, motion="G00"))
            lines.append(at(i, c + near * u, motion="G00"))
            lines.append(at(i, c + (touch_radius_mm - overtravel_mm) * u, motion="G31", feed=feed,
                            note="probe: record the trigger position"))
            lines.append(at(i, c + near * u, motion="G00"))
            if j:
                lines.append(at(i, over, motion="G00"))
        lines.append(at(i, c - far * s[i], motion="G00", note="back off"))
    lines.append("M30")
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- one program of a campaign
def campaign_program(campaign, *, pattern: str | None = None, run: int | None = None, probe: str | None = None,
                     rtest: str | None = None, setup: str | None = None, mount: str | None = None, arc_deg=None,
                     step_deg: float | None = None, hold_deg: dict | None = None, feed: float | None = None,
                     dwell_ms: int | None = None, options: dict | None = None) -> str:
    """The program ``ncgen`` writes, on every machine: of the campaign's ``run``-th ball-bar run (1-based, the
    measured then the planned ones), of its probe run ``probe`` (id, or 1-based number), of its R-test run ``rtest``
    (id, or 1-based number; ``dwell_ms`` its dwell at each position, :mod:`.rtest_program`), or of ``pattern`` at
    ``setup``/``mount`` (default: those of the campaign's first run of the pattern, else its first set-up and the
    first mount that serves the pattern) over ``arc_deg`` = (start, end) degrees by ``step_deg``
    (default the format's step, else 1°; without ``arc_deg`` the campaign format's or the axis' grid) with
    ``hold_deg`` {letter: degrees}; in the machine's program format (:func:`program_format`) with ``options`` its own
    {name: value} (None: not given).  An option the format does not take is refused by name."""
    fmt = program_format(campaign.machine)
    options = {k: v for k, v in (options or {}).items() if v is not None}
    for name in options:
        if name not in fmt.options:
            raise ParameterError(name, f"not an option of this machine's program format ({fmt.name}, which takes "
                                 + (", ".join(fmt.options) if fmt.options else "no options of its own") + ")")
    chosen = [name for name, v in (("pattern", pattern), ("run", run), ("probe", probe), ("rtest", rtest))
              if v is not None]
    if len(chosen) != 1:
        raise ParameterError("pattern", "give one of a pattern, a run number (run), a probe run (probe) or an R-test "
                             "run (rtest)" + (f", not {' and '.join(chosen)}" if chosen else ""))
    if dwell_ms is not None and rtest is None:
        raise ParameterError("dwell_ms", "only with an R-test run: the dwell at its positions")
    if pattern is None:
        extra = next((k for k, v in (("setup", setup), ("mount", mount), ("arc_deg", arc_deg),
                                     ("hold_deg", hold_deg)) if v is not None), None)
        if extra is not None:
            raise ParameterError(extra, f"only with a pattern: the {chosen[0]} has its own")
    if rtest is not None:
        if options:
            raise ParameterError(next(iter(options)), "an option of a ball-bar program, not of an R-test run's")
        if step_deg is not None:
            raise ParameterError("step_deg", "an option of a ball-bar program: an R-test run has its own positions")
        return rtest_program(campaign, rtest_run(campaign, rtest),
                             **{k: v for k, v in (("feed", feed), ("dwell_ms", dwell_ms)) if v is not None})
    if probe is not None:
        if options:
            raise ParameterError(next(iter(options)), "an option of a ball-bar program, not of a probe run's")
        return probe_program(campaign, _probe_run(campaign, probe), **({} if feed is None else {"feed": feed}))
    if run is not None:
        runs = [*campaign.ballbar.runs, *campaign.ballbar.planned]  # as the file is saved: measured, then planned
        if not runs:
            raise InputError(campaign.source, "ballbar.runs", f"no ball-bar runs, measured or planned: no run {run} "
                             "to write a program of (a probe run's program: give its id or number instead)")
        if not 1 <= run <= len(runs):
            raise ParameterError("run", f"the campaign has {len(runs)} ball-bar runs: 1 to {len(runs)}")
        return ballbar_program(campaign, runs[run - 1], feed=feed, step_deg=step_deg, options=options)
    one = _pattern_run(campaign, pattern, setup=setup, mount=mount, arc_deg=arc_deg, hold_deg=hold_deg)
    if arc_deg is not None and step_deg is None:
        step_deg = fmt.step_deg or ARC_STEP_DEG
    return ballbar_program(campaign, one, feed=feed, step_deg=step_deg, options=options)


def _probe_run(campaign, probe: str):
    return measured_run(campaign, campaign.probe.runs if campaign.probe is not None else [], probe, section="probe",
                        what="probe run", hint=" (a ball-bar run's program: give its number or a pattern instead)")


def _pattern_run(campaign, pattern: str, *, setup, mount, arc_deg, hold_deg) -> Run:
    """The :class:`Run` of ``pattern`` that :func:`campaign_program` writes (no readings): its arc the two ends of
    ``arc_deg``, which the format grids."""
    bb = campaign.ballbar
    for key, have, what in (("ballbar.setups", bb.setups, "tool setup"), ("ballbar.mounts", bb.mounts, "W-ball mount")):
        if not have:
            raise InputError(campaign.source, key, f"no {what}: a ball-bar program of {pattern} needs the campaign's "
                             "[ballbar] with its tool setups and W-ball mounts")
    same = next((r for r in bb.runs if r.pattern == pattern), None)
    setup = setup or (same.setup if same else next(iter(bb.setups)))
    mount = mount or (same.mount if same else _serving_mount(campaign, pattern))
    arc = None
    if arc_deg is not None:
        lo, hi = (float(x) for x in arc_deg)
        if not (np.isfinite([lo, hi]).all() and lo < hi):
            raise ParameterError("arc_deg", f"expected start < end, got {lo:g} {hi:g}")
        arc = np.array([lo, hi])
    return Run(pattern, setup, mount, arc_deg=arc, hold_deg=dict(hold_deg) if hold_deg else None)


def _serving_mount(campaign, pattern: str) -> str:
    """The first mount that serves ``pattern`` in the campaign's format (its plug-in's ``mount_conflict``), one whose
    W ball is off the line of the swivelled axis first where that axis carries the workpiece (a ball on its line
    stays where it is)."""
    conflict = provided(campaign.machine, "mount_conflict")
    mounts = [m for m in campaign.ballbar.mounts.values() if conflict is None or conflict(pattern, m) is None]
    mounts = mounts or list(campaign.ballbar.mounts.values())
    try:
        ax = axis_of(description_of(campaign.machine), pattern)
    except ValueError:
        return mounts[0].id  # the pattern is refused by name when checked
    if ax.work_side:
        off = [m for m in mounts if np.linalg.norm(np.cross(m.centre() - ax.point, ax.direction)) > 1e-9]
        mounts = off or mounts
    return mounts[0].id
