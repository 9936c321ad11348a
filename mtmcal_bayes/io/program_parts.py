"""What the measuring programs of every kind share (:mod:`.chain_programs`, :mod:`.rtest_program`): the campaign's
name in a header, the travel checks and notes, the spindle's direction at a pose, a pose moved by an offset, and the
nominal relative position of a tool-side and a workpiece-side point at commands.  Units: mm and rad in, degrees in
words."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import units
from ..errors import InputError, ParameterError
from ..machines.description import FRAME
from ..machines.patterns import nominal_down

#: how far the tool backs off along its axis before the rotary axes move, mm
RETRACT_MM = 50.0


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


def _positive(name: str, value) -> None:
    if not (np.isfinite(value) and value > 0):
        raise ParameterError(name, f"must be a positive number, got {value}")


def measured_run(campaign, runs: list, wanted: str, *, section: str, what: str, hint: str = ""):
    """The run of ``runs`` (a campaign's ``[[<section>.runs]]``) that ``wanted`` names: its id, or its 1-based number.
    None there: an :class:`InputError` naming ``<section>.runs`` (``hint`` added); an unknown one: a
    :class:`ParameterError` naming ``section``.  ``what``: the run's kind in the messages ("probe run")."""
    if not runs:
        raise InputError(campaign.source, f"{section}.runs", f"no [[{section}.runs]]: no {what} {wanted!r} to write "
                         f"a program of{hint}")
    ids = [r.id for r in runs]
    if wanted in ids:
        return runs[ids.index(wanted)]
    if str(wanted).isdigit() and 1 <= int(wanted) <= len(runs):
        return runs[int(wanted) - 1]
    raise ParameterError(section, f"no {what} {wanted!r} in the campaign (have: {', '.join(ids)}, or 1 to "
                         f"{len(runs)})")
