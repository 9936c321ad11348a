"""The reading frames of every machine's ball-bar patterns, from its chain (SPEC §17 on every machine, SPEC §19).

A run's reading convention (:mod:`mtmcal_bayes.conventions`) says where the ball-bar software drew the samples at 0°
and 90° of the motion; what it is read against is the pattern's frame.  On a machine from its description the
pattern ``<K><d>`` has the components of :func:`~mtmcal_bayes.machines.patterns.components` (``ex, ey`` about Z;
``ez, ex`` about Y; ``ey, ez`` about X), the machine frame's sample at angle ψ standing for ``(cos ψ, sin ψ)`` along
them, ψ the commanded angle of K (for a radial pattern the polar angle of the bar, :func:`~mtmcal_bayes.machines.
patterns.pattern_commands`), and the ``"machine"`` convention's directions those of the programmed linear position
from the programmed arc's centre.  The thesis' patterns are read against these too (their campaign in the chain's
terms: ``plugins/thesis/translation.py``): they are the frames of Tables 2.2/2.3 (``tests/test_conventions_machines.py``).
"""

from __future__ import annotations

import numpy as np

from .conventions import ConventionError, PatternFrame
from .machines.description import MachineDescription
from .machines.patterns import components, pattern_commands

#: the motion angles, degrees, at which a frame is read: 0° and 90°, and half a turn on for the arc's centre
_ANGLES = np.array([0.0, 90.0, 180.0, 270.0])


def chain_frame(desc: MachineDescription, run, ballbar) -> PatternFrame:
    """The :class:`~mtmcal_bayes.conventions.PatternFrame` of ``run`` (a run or planned run of ``ballbar``) on the
    machine ``desc``, at its set-up's tool length, its mount's W-ball position, the bar length and its held axes."""
    comps = components(desc, run.pattern)
    axes = tuple(c[1].upper() for c in comps)
    setup, mount = ballbar.setups[run.setup], ballbar.mounts[run.mount]

    try:
        cmd = pattern_commands(desc, run.pattern, length=setup.R_B, ball=mount.centre(), bar=ballbar.length,
                               arc_deg=_ANGLES, hold_deg=run.hold_deg, reverse=ballbar.bar_reversed(run))
    except ValueError as err:
        raise ConventionError(str(err)) from None
    basis = np.c_[np.cos(cmd.psi[:2]), np.sin(cmd.psi[:2])]

    def programmed() -> np.ndarray:
        q = cmd.q
        pts = np.c_[q[axes[0]], q[axes[1]]]
        centre = 0.5 * (pts[0] + pts[2])  # the commands are circles in the angle: half a turn apart
        d = pts[:2] - centre
        norm = np.linalg.norm(d, axis=1, keepdims=True)
        if np.any(norm < 1e-9):
            raise ConventionError(f"pattern {run.pattern}: the programmed {'/'.join(axes)} position does not turn "
                                  "with the axis, so the \"machine\" convention has no directions; give where the "
                                  f"samples at 0° and 90° were drawn (\"{run.pattern[0]}0=...,{run.pattern[0]}90=...\")")
        return d / norm

    return PatternFrame(run.pattern[0], comps, axes, basis, programmed, run.pattern)


__all__ = ["chain_frame"]
