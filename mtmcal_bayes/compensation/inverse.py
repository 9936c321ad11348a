"""The X/Y/Z that put the tool point where programmed, and the tilt of the tool axis, through any machine's kinematics.

A *kinematics* is what a machine's compensation inverts: an object with

* ``tool_point(q, dev, *, n=1)`` — the tool point ``(n, k, 3)`` mm in the workpiece frame (as its place at the
  home pose: what a cutting tool leaves on the part) for commands ``q`` ``{letter: (k,)}`` (X, Y, Z mm as the
  program writes them, rotary axes rad) and deviation values ``dev`` ``{name: (n,)}`` (mm, rad; ``{}``: the
  nominal machine, one row);
* ``tool_axis(q, dev, *, n=1)`` — the unit direction ``(n, k, 3)`` of the tool at that point, nose to tip;
* ``model`` (its name, as the result states it) and ``info`` (what the result states of its geometry).

The engine's is the description's chain (:mod:`.chain_kinematics`); a plug-in may give its own (the thesis
machine's: its published models in their model frame).

The linear axes sit nearer the bed than every rotary axis, so the tool point is affine in X, Y, Z at fixed rotary
positions: the Jacobian from unit steps is exact, and Newton on all blocks at once reaches rounding level in two
iterations; three are done.
"""

from __future__ import annotations

import numpy as np

#: the linear axes, the ones a compensation rewrites
LINEAR = ("X", "Y", "Z")
#: Newton iterations of :func:`invert` (the map is affine in X/Y/Z: two reach rounding level)
ITERATIONS = 3


def with_xyz(q: dict[str, np.ndarray], xyz: np.ndarray) -> dict[str, np.ndarray]:
    """``q`` with X, Y, Z replaced by the columns of ``xyz`` ``(k, 3)`` mm."""
    return {**q, **{a: xyz[:, i] for i, a in enumerate(LINEAR)}}


def invert(kin, q: dict[str, np.ndarray], dev: dict[str, float], *,
           iterations: int = ITERATIONS) -> tuple[np.ndarray, float]:
    """X, Y, Z ``(k, 3)`` mm that bring the tool point of ``kin`` with deviations ``dev`` (``{name: value}``, mm
    and rad) onto its nominal tool point at the programmed commands ``q`` (the rotary axes kept as programmed); and
    the largest remaining miss, mm (rounding level).

    Each iteration evaluates the point and its three unit steps as one call over four copies of the blocks (no loop
    over blocks; any kinematics that takes ``(k,)`` commands serves)."""
    target = kin.tool_point(q, {})[0]
    k = len(target)
    x = np.stack([np.asarray(q[a], dtype=float) for a in LINEAR], axis=-1)  # (k, 3)
    one = {name: np.array([value], dtype=float) for name, value in dev.items()}
    rotary = {a: np.tile(np.asarray(v, dtype=float), 4) for a, v in q.items() if a not in LINEAR}
    steps = np.vstack([np.zeros(3), np.eye(3)])  # (4, 3): the point, then a 1 mm step of X, Y, Z
    for _ in range(iterations):
        trial = (x[None] + steps[:, None, :]).reshape(4 * k, 3)
        p = kin.tool_point(with_xyz(rotary, trial), one)[0].reshape(4, k, 3)
        J = np.stack([p[i + 1] - p[0] for i in range(3)], axis=-1)  # (k, 3, 3): d point / d (X, Y, Z)
        x = x - np.linalg.solve(J, (p[0] - target)[..., None])[..., 0]
    miss = kin.tool_point(with_xyz(q, x), one)[0] - target
    return x, float(np.abs(miss).max())


def tool_axis_tilt(kin, q: dict[str, np.ndarray], dev: dict[str, np.ndarray], *, n: int = 1) -> np.ndarray:
    """Angle ``(n, k)`` rad between the actual and the nominal tool axis in the workpiece frame: what moving X, Y,
    Z (a translation) cannot correct.  ``dev`` ``{name: (n,)}``: e.g. one deviation per row."""
    cos = np.sum(kin.tool_axis(q, dev, n=n) * kin.tool_axis(q, {}), axis=-1)
    return np.arccos(np.clip(cos, -1.0, 1.0))
