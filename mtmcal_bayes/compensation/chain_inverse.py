"""The tool point of a described machine in its workpiece frame, and the X/Y/Z that put it where programmed.

A program's words are the axes' positions (X, Y, Z mm; the rotary axes' by their letters, rad here), as the
description's commands are (:mod:`mtmcal_bayes.models.chain`).  The tool point — the tool centre ``length`` mm
along the spindle from its ``point_mm`` — is taken down the tool side to the bed and back up the workpiece side
(:meth:`~mtmcal_bayes.models.chain.Chain.work_frame`): where it sits on the workpiece, as its place at the home
pose, which is what a cutting tool leaves on the part.  With no deviations that is the programmed point.

The linear axes sit nearer the bed than every rotary axis (:mod:`mtmcal_bayes.machines.description`), so the
tool point is affine in X, Y, Z at fixed rotary positions: the Jacobian from unit steps is exact, and Newton on
all blocks at once reaches rounding level in two iterations; three are done.

Shapes: ``k`` blocks, ``n`` draws (or single-deviation rows), ``d`` deviations; deviation values ``{name: (n,)}``
in mm and rad; points ``(n, k, 3)`` mm.
"""

from __future__ import annotations

import numpy as np

from ..machines.description import LINEAR
from ..machines.patterns import tool_home
from ..models.chain import Chain

#: Newton iterations of :func:`invert` (the map is affine in X/Y/Z: two reach rounding level)
ITERATIONS = 3


def work_tool_point(chain: Chain, length: float, q: dict[str, np.ndarray], dev: dict[str, np.ndarray], *,
                    n: int = 1) -> np.ndarray:
    """Tool point ``(n, k, 3)`` mm in the workpiece frame for commands ``q`` ``{letter: (k,) or (n, k)}`` (mm, rad)
    and deviation values ``dev`` ``{name: (n,)}`` (``{}``: the nominal machine), a tool ``length`` mm long."""
    k = max(np.shape(v)[-1] for v in q.values())
    t = np.broadcast_to(tool_home(chain.desc, length), (n, k, 3)).copy()
    return chain.work_frame(chain.tool_point(t, q, dev), q, dev)


def invert(chain: Chain, length: float, q: dict[str, np.ndarray], dev: dict[str, float], *,
           iterations: int = ITERATIONS) -> tuple[np.ndarray, float]:
    """X, Y, Z ``(k, 3)`` mm that bring the tool point of the machine with deviations ``dev`` (``{name: value}``,
    mm and rad) onto the nominal tool point of the programmed commands ``q`` (``{letter: (k,)}``, mm and rad; the
    rotary axes kept as programmed); and the largest remaining miss, mm (rounding level).

    Each iteration evaluates the point and its three unit steps as four rows of one call (no loop over blocks)."""
    target = work_tool_point(chain, length, q, {})[0]
    x = np.stack([np.asarray(q[a], dtype=float) for a in LINEAR], axis=-1)  # (k, 3)
    dev4 = {name: np.full(4, value, dtype=float) for name, value in dev.items()}
    steps = np.vstack([np.zeros(3), np.eye(3)])  # (4, 3): the point, then a 1 mm step of X, Y, Z
    for _ in range(iterations):
        trial = x[None] + steps[:, None, :]  # (4, k, 3)
        qq = {**q, **{a: trial[..., i] for i, a in enumerate(LINEAR)}}
        p = work_tool_point(chain, length, qq, dev4, n=4)  # (4, k, 3)
        J = np.stack([p[i + 1] - p[0] for i in range(3)], axis=-1)  # (k, 3, 3): d point / d (X, Y, Z)
        x = x - np.linalg.solve(J, (p[0] - target)[..., None])[..., 0]
    miss = work_tool_point(chain, length, {**q, **{a: x[:, i] for i, a in enumerate(LINEAR)}},
                           {name: np.array([v], dtype=float) for name, v in dev.items()})[0] - target
    return x, float(np.abs(miss).max())


def tool_axis_tilt(chain: Chain, length: float, q: dict[str, np.ndarray], dev: dict[str, np.ndarray], *,
                   n: int = 1) -> np.ndarray:
    """Angle ``(n, k)`` rad between the actual and the nominal tool axis in the workpiece frame: what moving X, Y,
    Z (a translation) cannot correct.  ``dev`` ``{name: (n,)}``: e.g. one deviation per row."""
    def axis(d, rows):  # the unit vector from the tool point 1 mm further along the tool
        v = work_tool_point(chain, length + 1.0, q, d, n=rows) - work_tool_point(chain, length, q, d, n=rows)
        return v / np.linalg.norm(v, axis=-1, keepdims=True)

    cos = np.sum(axis(dev, n) * axis({}, 1), axis=-1)
    return np.arccos(np.clip(cos, -1.0, 1.0))
