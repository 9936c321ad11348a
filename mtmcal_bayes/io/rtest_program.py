"""The measuring NC program of an R-test run (``ncgen --rtest``, SPEC §22 "Program"), in the engine's format.

At each position of the run the rotary axes are at the run's angles and the linear axes at the commands that put
the nominal nest centre on the nominal sphere centre through the nominal inverse chain
(:func:`~mtmcal_bayes.machines.patterns.centre_commands`: the same numbers as the R-test model's
:class:`~mtmcal_bayes.models.rtest.RTestLayout`), so the readings are what the model predicts.  The program: the
rotary axes to the first position with the nest backed off along the spindle, a stop to set the sphere and nest,
then per position one ``G01`` block with every axis word and a dwell ``G04 P<ms>`` while the sensors read (a stop
to zero them after the first where the run is zeroed there), the nest backed off at the end.

Controller-specific, and said in the header: the dwell word (``G04 P`` in milliseconds is Fanuc-type; Siemens
``G4 F<s>``, Heidenhain cycle 9), the axis letters (the description's, ISO word order), the NC frame (the
description's commands, every axis 0 at the home pose), and the feed of a block that moves rotary and linear axes
together.  Between two blocks the control moves each axis linearly, so the nest centre leaves the sphere centre
between positions; the header states by how much (the nominal gap at intermediate points of each move), the
controller's tool-centre-point function (TRAORI, M128, G43.4) or closer positions keep it small.
"""

from __future__ import annotations

import numpy as np

from ..errors import ParameterError
from ..machines.description import FRAME
from ..machines.patterns import centre_commands, tool_home
from ..units import fixed
from .machine_reader import description_of
from .nc_axes import DECIMALS, axis_block, axis_letters, comment
from .program_parts import (
    measured_run,
    RETRACT_MM,
    _deg,
    _linear_notes,
    _name,
    _rotary_travel,
    _tool_direction,
    relative_position,
)

#: the dwell at each position for the sensors' reading, milliseconds (the unit of a Fanuc-type ``G04 P``)
DWELL_MS = 2000
#: the feed of the blocks between positions, mm/min (a slow move: the sphere stays in the nest)
RTEST_FEED = 200.0
#: intermediate points per move at which the gap between nest and sphere centres is computed
SUBSTEPS = 32


def rtest_run(campaign, run: str):
    """The ``[[rtest.runs]]`` run ``run`` (its id, or its 1-based number) of ``campaign``; an :class:`InputError`
    naming ``rtest.runs`` where the campaign has none, a :class:`ParameterError` naming ``rtest`` for an unknown
    one."""
    return measured_run(campaign, campaign.rtest.runs if campaign.rtest is not None else [], run, section="rtest",
                        what="R-test run")


def rtest_commands(campaign, run) -> dict:
    """The commands {letter: (k,)} (mm, rad) of ``run``'s positions: every rotary axis at the run's angles (0 where
    it names none), the linear axes through the nominal inverse chain."""
    desc = description_of(campaign.machine)
    k = run.positions
    q_rot = {a.letter: np.broadcast_to(np.asarray(run.angles.get(a.letter, 0.0), float), (k,)).copy()
             for a in desc.rotary_axes}
    tool = tool_home(desc, campaign.rtest.nests[run.nest].length)
    return {**q_rot, **centre_commands(desc, q_rot, tool=tool, point=np.asarray(run.sphere, float))}


def _gap(desc, q: dict, tool: np.ndarray, sphere: np.ndarray) -> float:
    """The largest nominal distance, mm, between nest and sphere centres while each axis moves linearly from one
    position of ``q`` {letter: (k,)} to the next (:data:`SUBSTEPS` points per move)."""
    k = len(q["X"])
    if k < 2:
        return 0.0
    t = np.arange(1, SUBSTEPS) / SUBSTEPS
    between = {a: (v[:-1, None] + (v[1:] - v[:-1])[:, None] * t).reshape(-1) for a, v in q.items()}
    return float(np.linalg.norm(relative_position(desc, between, tool=tool, ball=sphere), axis=-1).max())


def rtest_program(campaign, run, *, dwell_ms: int = DWELL_MS, feed: float = RTEST_FEED,
                  decimals: int = DECIMALS) -> str:
    """The NC program of R-test run ``run`` (a :class:`~mtmcal_bayes.campaign.RTestRun`) of ``campaign`` as text
    (the module docstring); ``dwell_ms`` the dwell at each position, ms (a whole number); ``feed`` of the moves,
    mm/min."""
    if isinstance(dwell_ms, bool) or not float(dwell_ms).is_integer() or not dwell_ms > 0:
        raise ParameterError("dwell_ms", f"must be a positive whole number of milliseconds, got {dwell_ms}")
    if not (np.isfinite(feed) and feed > 0):
        raise ParameterError("feed", f"must be a positive number, got {feed}")
    ms = int(dwell_ms)
    desc = description_of(campaign.machine)
    nest = campaign.rtest.nests[run.nest]
    q = rtest_commands(campaign, run)
    for ax in desc.rotary_axes:
        _rotary_travel(ax, _deg(q[ax.letter]), "rtest")
    letters = axis_letters(desc)
    rotary = [a for a in letters if a not in FRAME]
    k = run.positions
    tool, sphere = tool_home(desc, nest.length), np.asarray(run.sphere, float)
    gap = _gap(desc, q, tool, sphere)
    s = _tool_direction(desc, {a: q[a][[0, -1]] for a in rotary})  # the spindle at the first and last positions

    def block(i, motion, *, offset=np.zeros(3), **kw):
        pose = {a: float(q[a][i] + offset[j]) for j, a in enumerate(FRAME)}
        pose.update({a: float(_deg(q[a][i])) for a in rotary})
        return axis_block({a: pose[a] for a in letters}, motion=motion, decimals=decimals, **kw)

    header = [
        f"mtmcal-bayes measuring program: R-test run {run.id} of {_name(campaign)}",
        f"machine: {desc.name or 'described machine'}, {desc.configuration}",
        f"nest {run.nest}: its centre {nest.length:g} mm from the spindle point along the spindle; sphere at "
        + " ".join(f"{a}{v:g}" for a, v in zip(FRAME, sphere)) + f" mm at the home pose; {k} positions of "
        + (" ".join(rotary) or "no rotary axis") + f"; frame {run.frame}, zero {run.zero}",
        "axis words: the description's commands, mm and deg, absolute, every axis 0 at the home pose; run in the "
        "coordinate system in which these are the axis positions - the NC frame and the axis letters are this "
        "description's: map them to your control's",
        "per position: one block, the linear axes from the nominal inverse chain (the nest centre on the sphere "
        f"centre), then a dwell G04 P{ms} [{ms} ms] while the sensors read - G04 P in milliseconds is "
        "Fanuc-type; Siemens G4 F<s>, Heidenhain cycle 9 DWELL TIME: change it for your control",
        f"between the blocks each axis moves linearly: the nest centre leaves the sphere centre by up to {gap:.3f} mm "
        "- keep it within the sensors' range: the control's tool-centre-point function [TRAORI, M128, G43.4] or "
        "closer positions",
        *_linear_notes(desc, {a: np.concatenate([q[a], q[a][[0, -1]] - RETRACT_MM * s[:, FRAME.index(a)]])
                              for a in FRAME}),
        f"feed F{feed:g} on the moves between positions: the control's feed of a rotary-and-linear move",
    ]
    lines = [comment(h) for h in header] + ["G90 G21"]
    lines += [comment("rotary axes to the first position, the nest backed off along the spindle"),
              block(0, "G00", offset=-RETRACT_MM * s[0]),
              "M00 " + comment("set the sphere and the nest; the next block brings the nest onto the sphere")]
    for i in range(k):
        where = " ".join(f"{a}{fixed(float(_deg(q[a][i])), decimals)}" for a in rotary)
        lines.append(block(i, "G01", feed=feed, note=f"position {i + 1} of {k}" + (f": {where}" if where else "")))
        lines.append(f"G04 P{ms} " + comment("read the sensors"))
        if i == 0 and run.zero == "first":
            lines.append("M00 " + comment("zero the sensors here: the run is zeroed at its first position"))
    lines += [block(k - 1, "G00", offset=-RETRACT_MM * s[-1], note="back off"), "M30"]
    return "\n".join(lines) + "\n"
