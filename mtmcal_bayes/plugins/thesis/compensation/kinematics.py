"""Where the tool centre point actually is, relative to the workpiece: the thesis machine's kinematics of a
compensation, which the engine's Newton inverts (:mod:`mtmcal_bayes.compensation.inverse`).

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
    return tool_point_rad(theta, geo, xyz, (np.radians(bc_deg[:, 0]), np.radians(bc_deg[:, 1])), model=model,
                          point=point)


def tool_point_rad(theta: np.ndarray, geo: Geometry, xyz: np.ndarray, bc: tuple[np.ndarray, np.ndarray], *,
                   model: str = "htm-thesis", point: str = "tcp") -> np.ndarray:
    """:func:`tool_point` with ``bc`` = (B, C), each ``(k,)`` rad."""
    B, C = bc
    piv = PIVOTS[model]
    p = deviation_dict(theta)
    if point == "nose":
        p["dRB"] = np.full(len(p["dx_BT"]), -geo.Z_T)  # the tool vector ends Z_T short of the ball
    cmd = Commands(xyz[:, 0], xyz[:, 1], xyz[:, 2], B, C, B)
    T = t_ball(p, geo, cmd, piv)  # (n, k, 3) machine frame
    Tc = CAxis(p, geo.Z_C, piv).to_table(T)  # C-axis frame (Eq 2.16)
    # turn back by C: the workpiece (table) frame
    cC, sC = np.cos(C), np.sin(C)
    x = cC * Tc[..., 0] + sC * Tc[..., 1]
    y = -sC * Tc[..., 0] + cC * Tc[..., 1]
    return np.stack([x, y, Tc[..., 2]], axis=-1)


class ModelFrameKinematics:
    """The thesis machine's kinematics for the engine's compensation (:mod:`mtmcal_bayes.compensation.inverse`):
    the tool point of its model ``model`` (``htm-thesis``: its pivots; ``htm-literal``: the chain) at the lever arms
    ``geo``, the tool centre (``point="tcp"``) or the spindle nose (``"nose"``).  Commands ``{X, Y, Z (k,) mm, B,
    C (k,) rad}`` are the program's, whose origin sits at ``origin`` ``(3,)`` mm of the model frame (a program
    in the thesis' NC frame: :func:`~mtmcal_bayes.plugins.thesis.htm.nc_origin`; commands of its model: zero);
    deviations ``{thesis name: (n,)}`` mm and rad."""

    def __init__(self, geo: Geometry, model: str, *, point: str, origin: np.ndarray, info: dict | None = None):
        self.geo, self.model, self.point, self.origin = geo, model, point, np.asarray(origin, dtype=float)
        self.info = dict(info or {})

    def _theta(self, dev: dict, n: int) -> np.ndarray:
        theta = np.zeros((n, len(DEVIATIONS)))
        for i, name in enumerate(DEVIATIONS):
            if name in dev:
                theta[:, i] = dev[name]
        return theta

    def _at(self, q, dev, n: int, point: str) -> np.ndarray:
        xyz = np.stack([q["X"], q["Y"], q["Z"]], axis=-1) + self.origin
        bc = (np.asarray(q["B"], dtype=float), np.asarray(q["C"], dtype=float))
        return tool_point_rad(self._theta(dev, n), self.geo, xyz, bc, model=self.model, point=point)

    def tool_point(self, q, dev, *, n: int = 1) -> np.ndarray:
        """The compensated point ``(n, k, 3)`` mm in the C-table frame."""
        return self._at(q, dev, n, self.point)

    def tool_axis(self, q, dev, *, n: int = 1) -> np.ndarray:
        """The tool's direction ``(n, k, 3)``, the nose to the tool centre (independent of X/Y/Z)."""
        v = self._at(q, dev, n, "tcp") - self._at(q, dev, n, "nose")
        return v / np.linalg.norm(v, axis=-1, keepdims=True)
