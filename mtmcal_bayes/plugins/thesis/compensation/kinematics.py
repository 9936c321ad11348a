"""Where the tool centre point actually is, relative to the workpiece, and the exact X/Y/Z inversion.

The tool point is followed through the kinematic chain of :mod:`~mtmcal_bayes.plugins.thesis.htm`
(spindle side, ``t_ball``) and expressed in the frame of the C table (the
workpiece), turned back by C: what a cutting tool would leave on the part.
Commands are in the model frame (the B-axis centre in the C-table frame,
``NC + origin``).  ``point="tcp"`` is the tool centre at the programmed tool
length R_B; ``point="nose"`` is the point Z_T up the spindle axis from it, about
which alpha_BT turns the tool in ``htm-thesis`` (the spindle nose the thesis
compensates, Sec 4.4.3).
"""

from __future__ import annotations

import numpy as np

from ..htm import PIVOTS, CAxis, Geometry, t_ball
from ....parameters import DEVIATIONS
from ..pattern_tables import Commands



def deviation_dict(theta: np.ndarray) -> dict[str, np.ndarray]:
    """``(n, 13)`` deviations in Table 2.1 order (internal units) to the parameter dict of ``t_ball``."""
    theta = np.atleast_2d(theta)
    p = {name: theta[:, i] for i, name in enumerate(DEVIATIONS)}
    zero = np.zeros(theta.shape[0])
    p.update(xT=zero, yT=zero, zT=zero, dRB=zero)
    return p


def tool_point(theta: np.ndarray, geo: Geometry, xyz: np.ndarray, bc_deg: np.ndarray, *, model: str = "htm-thesis",
               point: str = "tcp") -> np.ndarray:
    """Tool point in the C-table frame, ``(n, k, 3)`` mm, for deviations ``(n, 13)`` and commands ``(k, 3)``/``(k, 2)``."""
    piv = PIVOTS[model]
    p = deviation_dict(theta)
    if point == "nose":
        p["dRB"] = np.full(len(p["dx_BT"]), -geo.Z_T)  # the tool vector ends Z_T short of the ball
    B, C = np.radians(bc_deg[:, 0]), np.radians(bc_deg[:, 1])
    cmd = Commands(xyz[:, 0], xyz[:, 1], xyz[:, 2], B, C, B)
    T = t_ball(p, geo, cmd, piv)  # (n, k, 3) machine frame
    Tc = CAxis(p, geo.Z_C, piv).to_table(T)  # C-axis frame (Eq 2.16)
    # turn back by C: the workpiece (table) frame
    cC, sC = np.cos(C), np.sin(C)
    x = cC * Tc[..., 0] + sC * Tc[..., 1]
    y = -sC * Tc[..., 0] + cC * Tc[..., 1]
    return np.stack([x, y, Tc[..., 2]], axis=-1)


def compensate_exact(theta: np.ndarray, geo: Geometry, xyz: np.ndarray, bc_deg: np.ndarray, *,
                     model: str = "htm-thesis", point: str = "tcp", iterations: int = 4) -> tuple[np.ndarray, float]:
    """X, Y, Z ``(k, 3)`` that bring the actual tool point onto the nominal one; and the largest miss, mm.

    Newton on the three linear axes per block, B and C as programmed.  The tool
    point is affine in X, Y, Z, so the Jacobian from unit steps is exact and two
    iterations reach rounding level; four are done.
    """
    theta = np.atleast_2d(theta)[:1]
    target = tool_point(np.zeros_like(theta), geo, xyz, bc_deg, model=model, point=point)[0]
    x = np.array(xyz, dtype=float)
    for _ in range(iterations):
        base = tool_point(theta, geo, x, bc_deg, model=model, point=point)[0]
        J = np.stack([tool_point(theta, geo, x + e, bc_deg, model=model, point=point)[0] - base for e in np.eye(3)],
                     axis=-1)
        x = x - np.linalg.solve(J, (base - target)[..., None])[..., 0]
    miss = tool_point(theta, geo, x, bc_deg, model=model, point=point)[0] - target
    return x, float(np.abs(miss).max())


def tool_axis_tilt(theta: np.ndarray, geo: Geometry, xyz: np.ndarray, bc_deg: np.ndarray, *,
                   model: str = "htm-thesis") -> np.ndarray:
    """Tilt of the tool axis against the nominal one in the workpiece frame, ``(n, k)`` rad.

    Independent of the X/Y/Z commands: what moving the linear axes cannot correct.
    """
    def axis(th):
        tip = tool_point(th, geo, xyz, bc_deg, model=model, point="tcp")
        nose = tool_point(th, geo, xyz, bc_deg, model=model, point="nose")
        v = tip - nose
        return v / np.linalg.norm(v, axis=-1, keepdims=True)

    actual, nominal = axis(theta), axis(np.zeros((1, len(DEVIATIONS))))
    return np.arccos(np.clip(np.sum(actual * nominal, axis=-1), -1.0, 1.0))
