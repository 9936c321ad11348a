"""Measuring NC programs of a described machine (SPEC §19): one ball-bar run, one touch-probe run.

Both are functions of the campaign's geometry only (setups, mounts, bar length, styli, spheres, the description),
so a designed campaign's planned runs get programs before anything is measured.

**Ball bar** (:func:`ballbar_program`).  A run ``<K><d>`` swivels rotary axis K over its arc while the linear
axes keep the tool ball at the bar length from the W ball along the pattern's direction d, the other rotary axes
held.  The commanded positions of every point are those of
:func:`mtmcal_bayes.machines.patterns.pattern_commands` — the very commands the ``chain`` and ``linear`` models
predict the run with — so measuring with the program gives what the model predicts.  The program: the rotary
axes to the start pose (held axes and K at its first angle) with the tool backed off along its axis, the start
point, a stop to mount the bar, one ``G01`` block per point of the arc with every axis word, a stop, the tool
backed off again.  Between two blocks the control moves each axis linearly, so the bar length is exact at the
blocks (the points the model reads) and off by a chord error between them; the header states it.

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

from numbers import Real
from pathlib import Path

import numpy as np

from .. import units
from ..campaign import Run
from ..errors import InputError, ParameterError
from ..machines.description import FRAME
from ..machines.plugins import provided
from ..machines.patterns import axis_of, default_arc_deg, nominal_down, pattern_commands, placement_commands, tool_home
from ..units import fixed
from .nc_axes import DECIMALS, axis_block, axis_letters, comment

#: how far the tool backs off along its axis before the rotary axes move, mm
RETRACT_MM = 50.0
#: probing: centre distance of stylus ball and sphere at contact (sphere radius + stylus-ball radius), mm —
#: e.g. a 25 mm sphere and a 5 mm stylus ball; give the real one
TOUCH_RADIUS_MM = 15.0
#: probing: the approach stops this far before contact, and the skip move aims this far past it, mm
CLEARANCE_MM, OVERTRAVEL_MM = 5.0, 2.0
#: probing feed of the skip moves, mm/min (the thesis' Fig 5.12: F100)
PROBE_FEED = 100.0
#: the chord error between blocks the header suggests a finer step for, mm
CHORD_MM = 0.001
#: what the bar direction of each pattern letter is, said in a header
_DIRECTION = {"R": "radial from the {K} line", "T": "tangential about the {K} line", "A": "along the {K} axis",
              "X": "along the machine X axis", "Y": "along the machine Y axis", "Z": "along the machine Z axis"}
_COMMANDS_NOTE = ("axis words: the description's commands, mm and deg, absolute, every axis 0 at the home pose; "
                  "run in the coordinate system in which these are the axis positions")


# --------------------------------------------------------------------------- shared
def _description(campaign):
    if provided(campaign.machine, "program") is not None:
        raise ParameterError("campaign", "this machine's programs come from its plug-in (the thesis machine's: its "
                             "pattern and setup, measuring_program); this module writes those of the chain's commands")
    return campaign.machine.description


def _name(campaign) -> str:
    """The campaign's file name (not its folder: a program travels to the machine without it)."""
    return Path(campaign.source).name if campaign.source else "the campaign"


def _deg(x):
    return units.from_internal(x, "deg")


def _rotary_travel(ax, angles_deg, parameter: str) -> None:
    """ParameterError naming ``parameter`` if an angle (degrees) of rotary axis ``ax`` leaves its travel."""
    if ax.travel is None:
        return
    lo, hi = _deg(np.asarray(ax.travel))
    a = np.atleast_1d(angles_deg)
    if a.min() < lo - 1e-9 or a.max() > hi + 1e-9:
        at = f"at {a[0]:g} deg" if len(a) == 1 else f"reaches {a.min():g}..{a.max():g} deg"
        raise ParameterError(parameter, f"{ax.letter} {at}, beyond its travel [{lo:g}, {hi:g}] deg")


def _linear_notes(desc, q: dict) -> list[str]:
    """A header note per linear axis whose commands (mm) leave its described travel."""
    notes = []
    for a in FRAME:
        ax = desc.axes[a]
        v = np.asarray(q[a])
        if ax.travel is not None and (v.min() < ax.travel[0] - 1e-9 or v.max() > ax.travel[1] + 1e-9):
            notes.append(f"note: {a} commands reach {v.min():.3f}..{v.max():.3f} mm, outside the described {a} travel "
                         f"[{ax.travel[0]:g}, {ax.travel[1]:g}] mm: check the description's travels and origin")
    return notes


def _words(letters, q: dict, i: int) -> dict:
    """Block words {letter: value} of point ``i`` of commands ``q`` (mm, rad -> mm, degrees)."""
    return {a: float(q[a][i]) if a in FRAME else float(_deg(q[a][i])) for a in letters}


def _tool_direction(desc, q_rot: dict) -> np.ndarray:
    """The spindle's direction ``(k, 3)`` at rotary commands ``q_rot`` {letter: (k,)}, machine frame."""
    k = len(next(iter(q_rot.values())))
    return nominal_down(np.broadcast_to(desc.spindle.direction, (k, 3)), desc.tool_chain, q_rot, directions=True)


def _shift(q: dict, i: int, offset: np.ndarray) -> dict:
    """Commands (each (1,)) of point ``i`` of ``q`` with the linear axes moved by ``offset`` (3,) mm: the tool
    moves by ``offset`` relative to the workpiece (either side's linear axes, ISO 841)."""
    out = {a: np.atleast_1d(v[i]) for a, v in q.items()}
    for j, a in enumerate(FRAME):
        out[a] = out[a] + offset[j]
    return out


def relative_position(desc, q: dict, *, tool: np.ndarray, ball: np.ndarray) -> np.ndarray:
    """Nominal tool point minus workpiece point ``(k, 3)`` mm at commands ``q`` {letter: (k,)} (mm, rad): ``tool``
    (3,) and ``ball`` (3,) given at the home pose on their sides."""
    k = len(np.atleast_1d(q["X"]))
    t = nominal_down(np.broadcast_to(tool, (k, 3)), desc.tool_chain, q)
    w = nominal_down(np.broadcast_to(ball, (k, 3)), desc.work_chain, q)
    return t - w + np.stack([np.atleast_1d(q[a]) for a in FRAME], axis=-1)


# --------------------------------------------------------------------------- ball bar
def run_arc_deg(desc, run, step_deg: float | None = None) -> np.ndarray:
    """The angles (degrees) a run swivels its axis through: its own (default: the axis' grid), or from its first
    to its last angle by ``step_deg``."""
    ax = axis_of(desc, run.pattern)
    arc = default_arc_deg(ax) if run.arc_deg is None else np.asarray(run.arc_deg, dtype=float)
    if step_deg is None:
        return arc
    if not (np.isfinite(step_deg) and step_deg > 0):
        raise ParameterError("step_deg", f"must be a positive number, got {step_deg}")
    grid = np.arange(arc[0], arc[-1] + 1e-9, step_deg)
    if len(grid) < 9:
        raise ParameterError("step_deg", f"{step_deg:g} deg gives fewer than 9 angles over [{arc[0]:g}, "
                             f"{arc[-1]:g}] deg: too few to read the eccentricities from")
    return grid


def _checked_run(campaign, desc, run, step_deg):
    """(axis, setup, mount, arc degrees, held {letter: degrees}) of ``run``, each checked (ParameterError)."""
    try:
        ax = axis_of(desc, run.pattern)
    except ValueError as err:
        raise ParameterError("pattern", str(err)) from None
    bb = campaign.ballbar
    for name, value, have in (("setup", run.setup, bb.setups), ("mount", run.mount, bb.mounts)):
        if value not in have:
            raise ParameterError(name, f"no {name} {value!r} in the campaign (have: {', '.join(have) or 'none'})")
    arc = run_arc_deg(desc, run, step_deg)
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
    return ax, bb.setups[run.setup], bb.mounts[run.mount], arc, held


def ballbar_commands(campaign, run, *, step_deg: float | None = None):
    """The nominal commands of ``run`` (:class:`~mtmcal_bayes.machines.patterns.PatternCommands`, mm and rad), as
    its program commands them: ``pattern_commands`` of its setup's tool length, mount, bar length, arc and holds."""
    desc = _description(campaign)
    _, setup, mount, arc, held = _checked_run(campaign, desc, run, step_deg)
    return _pattern_commands(campaign, desc, run, setup=setup, mount=mount, arc=arc, held=held)


def bar_length(campaign, run) -> float:
    """The bar length, mm, of ``run``: a planned run's own (``length_mm``), else the campaign's."""
    own = getattr(run, "length", None)  # a measured Run has the campaign's
    return campaign.ballbar.length if own is None else own


def _pattern_commands(campaign, desc, run, *, setup, mount, arc, held):
    try:
        return pattern_commands(desc, run.pattern, length=setup.R_B, ball=mount.centre(),
                                bar=bar_length(campaign, run), arc_deg=arc, hold_deg=held,
                                reverse=campaign.ballbar.bar_reversed(run))
    except ValueError as err:  # a pattern the description does not have
        raise ParameterError("pattern", str(err)) from None


def ballbar_program(campaign, run, *, feed: float | None = None, step_deg: float | None = None,
                    decimals: int = DECIMALS) -> str:
    """The measuring program of ball-bar ``run`` (a :class:`~mtmcal_bayes.campaign.Run`: pattern, setup, mount,
    ``arc_deg`` (None: the axis' grid), ``hold_deg``) of a described ``campaign``, as text (see the module
    docstring).  ``feed`` mm/min on the arc blocks (default the campaign's ``feed_mm_per_min``, else none);
    ``step_deg`` re-grids the run's arc from its first to its last angle; ``decimals`` of every axis word."""
    desc = _description(campaign)
    ax, setup, mount, arc, held = _checked_run(campaign, desc, run, step_deg)
    cmd = _pattern_commands(campaign, desc, run, setup=setup, mount=mount, arc=arc, held=held)
    bb = campaign.ballbar
    feed = feed if feed is not None else bb.feed_mm_per_min
    if feed is not None and not (np.isfinite(feed) and feed > 0):
        raise ParameterError("feed", f"must be a positive number, got {feed}")
    letters = axis_letters(desc)
    q, k = cmd.q, len(arc)
    tool = tool_home(desc, setup.R_B)
    s = _tool_direction(desc, {a.letter: q[a.letter][[0, -1]] for a in desc.rotary_axes})
    backed = [_shift(q, i, -RETRACT_MM * s[j]) for j, i in enumerate((0, k - 1))]
    mid = {a: 0.5 * (v[:-1] + v[1:]) for a, v in q.items()}
    bar = bar_length(campaign, run)
    chord = np.abs(np.linalg.norm(relative_position(desc, mid, tool=tool, ball=mount.centre()), axis=1) - bar)
    fine = (arc[1] - arc[0]) * np.sqrt(CHORD_MM / chord.max()) if k > 1 and chord.max() > 0 else None
    place = placement_commands(desc, length=setup.R_B, ball=mount.centre())
    every = {a: np.concatenate([np.atleast_1d(p[a]) for p in (q, *backed)]) for a in q}
    held_text = ", ".join(f"{a} {held.get(a, 0.0):g} deg" for a in sorted(held.keys() | {
        b.letter for b in desc.rotary_axes if b.letter != ax.letter})) or "none"
    step = f" by {arc[1] - arc[0]:g} deg" if k > 1 and np.allclose(np.diff(arc), arc[1] - arc[0]) else ""
    header = [
        f"mtmcal-bayes measuring program: ball-bar run {run.pattern} of {_name(campaign)}",
        f"machine: {desc.name or 'described machine'}, {desc.configuration}",
        f"pattern {run.pattern}: {ax.letter} from {arc[0]:g} to {arc[-1]:g} deg{step}, {k} points; bar "
        + _DIRECTION[run.pattern[1]].format(K=ax.letter) + f"; held: {held_text}",
        f"setup {run.setup}: tool length R_B {setup.R_B:g} mm from the spindle point; mount {run.mount}: W ball at "
        + " ".join(f"{a}{v:g}" for a, v in zip(FRAME, mount.centre())) + " mm at the home pose",
        f"bar {bar:g} mm; before this program the W ball is set where the dummy sphere in the spindle sits at "
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
    desc = _description(campaign)
    probe = campaign.probe
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
    tool = tool_home(desc, probe.styli[probe_run.stylus])
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
    positions, sphere, stylus) of a described ``campaign``, as text (see the module docstring).
    ``touch_radius_mm``: sphere radius plus stylus-ball radius; ``clearance_mm`` before contact,
    ``overtravel_mm`` past it; ``feed`` of the skip moves, mm/min."""
    desc = _description(campaign)
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
        f"stylus {probe_run.stylus}: length {campaign.probe.styli[probe_run.stylus]:g} mm from the spindle point; "
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
def described_program(campaign, *, pattern: str | None = None, run: int | None = None, probe: str | None = None,
                      setup: str | None = None, mount: str | None = None, arc_deg=None, step_deg: float | None = None,
                      hold_deg: dict | None = None, feed: float | None = None) -> str:
    """The program ``ncgen`` writes on a described machine: of the campaign's ``run``-th ball-bar run (1-based), of
    its probe run ``probe`` (id, or 1-based number), or of ``pattern`` at ``setup``/``mount`` (default: those of
    the campaign's first run of the pattern, else its first ones) over ``arc_deg`` = (start, end) degrees by
    ``step_deg`` (default 1°; without ``arc_deg`` the axis' grid) with ``hold_deg`` {letter: degrees}."""
    chosen = [name for name, v in (("pattern", pattern), ("run", run), ("probe", probe)) if v is not None]
    if len(chosen) != 1:
        raise ParameterError("pattern", "give one of a pattern, a run number (run) or a probe run (probe)"
                             + (f", not {' and '.join(chosen)}" if chosen else ""))
    if pattern is None:
        extra = next((k for k, v in (("setup", setup), ("mount", mount), ("arc_deg", arc_deg),
                                     ("hold_deg", hold_deg)) if v is not None), None)
        if extra is not None:
            raise ParameterError(extra, f"only with a pattern: the {chosen[0]} has its own")
    if probe is not None:
        return probe_program(campaign, _probe_run(campaign, probe), **({} if feed is None else {"feed": feed}))
    if run is not None:
        runs = [*campaign.ballbar.runs, *campaign.ballbar.planned]  # as the file is saved: measured, then planned
        if not runs:
            raise InputError(campaign.source, "ballbar.runs", f"no ball-bar runs, measured or planned: no run {run} "
                             "to write a program of (a probe run's program: give its id or number instead)")
        if not 1 <= run <= len(runs):
            raise ParameterError("run", f"the campaign has {len(runs)} ball-bar runs: 1 to {len(runs)}")
        return ballbar_program(campaign, runs[run - 1], feed=feed, step_deg=step_deg)
    one = _pattern_run(campaign, pattern, setup=setup, mount=mount, arc_deg=arc_deg, step_deg=step_deg,
                       hold_deg=hold_deg)
    return ballbar_program(campaign, one, feed=feed, step_deg=None if arc_deg is not None else step_deg)


def _probe_run(campaign, probe: str):
    runs = campaign.probe.runs if campaign.probe is not None else []
    if not runs:
        raise InputError(campaign.source, "probe.runs", f"no [[probe.runs]]: no probe run {probe!r} to write a "
                         "program of (a ball-bar run's program: give its number or a pattern instead)")
    ids = [r.id for r in runs]
    if probe in ids:
        return runs[ids.index(probe)]
    if str(probe).isdigit() and 1 <= int(probe) <= len(runs):
        return runs[int(probe) - 1]
    raise ParameterError("probe", f"no probe run {probe!r} in the campaign (have: {', '.join(ids) or 'none'})")


def _pattern_run(campaign, pattern: str, *, setup, mount, arc_deg, step_deg, hold_deg) -> Run:
    """The :class:`Run` of ``pattern`` that ``described_program`` writes (no readings)."""
    bb = campaign.ballbar
    for key, have, what in (("ballbar.setups", bb.setups, "tool setup"), ("ballbar.mounts", bb.mounts, "W-ball mount")):
        if not have:
            raise InputError(campaign.source, key, f"no {what}: a ball-bar program of {pattern} needs the campaign's "
                             "[ballbar] with its tool setups and W-ball mounts")
    same = next((r for r in bb.runs if r.pattern == pattern), None)
    setup = setup or (same.setup if same else next(iter(bb.setups), ""))
    mount = mount or (same.mount if same else next(iter(bb.mounts), ""))
    arc = None
    if arc_deg is not None:
        lo, hi = (float(x) for x in arc_deg)
        step = 1.0 if step_deg is None else step_deg
        if not (np.isfinite([lo, hi]).all() and lo < hi):
            raise ParameterError("arc_deg", f"expected start < end, got {lo:g} {hi:g}")
        if not (np.isfinite(step) and step > 0):
            raise ParameterError("step_deg", f"must be a positive number, got {step}")
        arc = np.arange(lo, hi + 1e-9, step)
        if len(arc) < 9:
            raise ParameterError("step_deg", f"{step:g} deg gives fewer than 9 angles over [{lo:g}, {hi:g}] deg: "
                                 "too few to read the eccentricities from")
    run = Run(pattern, setup, mount, arc_deg=arc, hold_deg=dict(hold_deg) if hold_deg else None)
    _checked_run(campaign, _description(campaign), run, None if arc is not None else step_deg)
    return run
