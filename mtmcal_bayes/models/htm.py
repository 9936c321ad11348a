"""Homogeneous-transform kinematic model of the ball-bar patterns (thesis Eqs 2.1–2.21, SPEC §3.2).

Spindle side (thesis Eq 2.10 with the T-ball offset of Eq 2.20)::

    T = E_Z M_YZ E_Y M_XY E_X M_XB E_B M_BT T_T,   T_T = (xT, yT, −(R_B + dRB) + zT)

Workpiece side (Eqs 2.13–2.16, 2.21): the W ball is placed once per mount at
the actual position P0 of the dummy sphere (true tool length, no ball offset,
B = 0, the commands of the mount's first run at zero angle), expressed in the
C-axis frame, offset by (xW, yW, zW), and turned with C::

    W(θ) = M_CZ E_C(θ) (M_CZ⁻¹ P0 + w),      ΔL = |T − W| − L_B

Rotations are exact (``expm([ε]×)`` through :mod:`scipy.spatial.transform`).
Where each angular deviation pivots is an explicit :class:`Pivots`
configuration; two are named:

* ``htm-literal`` — Eq 2.10 as printed: B-side angles about the B-axis centre,
  the C tilt about the table surface, linear-axis squareness about the frame origin.
* ``htm-thesis`` — pivots chosen so that the first-order response equals the
  thesis relations (the ``linear`` model): beta_XB tilts the Z travel about the NC
  origin (tool orientation unchanged); alpha_XB, gamma_XB rotate head, spindle and
  tool about the slide-fixed point (X_T, 0, Z_T) from the T ball; alpha_BT rotates
  about the spindle-axis point Z_T from the T ball; the C axis tilts about height
  2·Z_C, where dx_CZ, dy_CZ are its offsets; linear-axis squareness about the NC
  origin.  The NC origin is at (X_T, 0, Z_C + R_B + Z_T) in the model frame.

Everything is vectorised over the parameter batch (n) and the angle grid (k).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from ..patterns import Commands


@dataclass(frozen=True)
class Pivots:
    """Where the angular deviations of the kinematic chain pivot.

    alpha_BT : ``"b-centre"`` (origin of the spindle frame) or ``"tool-Z_T"``
        (on the spindle axis, Z_T from the T ball).
    xb_angles : pivot of alpha_XB, gamma_XB: ``"b-centre"`` or ``"slide-X_T-Z_T"``
        (slide-fixed, at (X_T, 0, Z_T) from the T ball at B = 0).
    beta_XB : ``"b-centre"`` (rotates head and tool about the B-axis centre) or
        ``"z-travel"`` (tilts the Z travel about the NC origin; tool orientation unchanged).
    c_tilt_height : ``"table"`` (height 0) or ``"2Z_C"``.
    origin : pivot of the linear-axis squareness: ``"frame"`` or ``"nc"`` (NC origin).
    """

    name: str
    alpha_BT: str
    xb_angles: str
    beta_XB: str
    c_tilt_height: str
    origin: str


HTM_LITERAL = Pivots("htm-literal", "b-centre", "b-centre", "b-centre", "table", "frame")
HTM_THESIS = Pivots("htm-thesis", "tool-Z_T", "slide-X_T-Z_T", "z-travel", "2Z_C", "nc")
PIVOTS = {p.name: p for p in (HTM_LITERAL, HTM_THESIS)}


@dataclass(frozen=True)
class Geometry:
    """Programmed lever arms of one run, mm: setup R_B, Z_T, X_T and mount Z_C, R_C."""

    R_B: float
    Z_T: float
    X_T: float
    Z_C: float
    R_C: float


def nc_origin(geo: Geometry) -> np.ndarray:
    """The NC origin in the model frame, ``(X_T, 0, Z_C + R_B + Z_T)`` mm."""
    return np.array([geo.X_T, 0.0, geo.Z_C + geo.R_B + geo.Z_T])


def rotation(rotvec: np.ndarray) -> np.ndarray:
    """Exact rotation matrices ``expm([ε]×)`` for rotation vectors ``(n, 3)`` -> ``(n, 3, 3)``."""
    return Rotation.from_rotvec(np.atleast_2d(rotvec)).as_matrix()


def _apply(R: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Apply per-draw rotations ``(n,3,3)`` to vectors ``(n,3)`` or ``(n,k,3)``."""
    Rt = np.transpose(R, (0, 2, 1))
    if v.ndim == 2:
        return (v[:, None, :] @ Rt)[:, 0, :]
    return v @ Rt  # batched matmul: far faster than einsum here


def t_ball(p: dict[str, np.ndarray], geo: Geometry, cmd: Commands, piv: Pivots, *,
           dummy: bool = False) -> np.ndarray:
    """Actual T-ball (or dummy-sphere) centre, shape ``(n, k, 3)``, mm.

    ``p`` maps parameter base names to arrays ``(n,)`` (internal units):
    the 13 deviations and, for this run's setup, ``xT, yT, zT, dRB``.
    ``dummy=True`` gives the dummy sphere: true tool length, no ball offset.
    """
    n = len(p["dx_BT"])
    zero = np.zeros(n)
    length = geo.R_B + p["dRB"]
    if dummy:
        t = np.stack([zero, zero, -length], axis=-1)
    else:
        t = np.stack([p["xT"], p["yT"], -length + p["zT"]], axis=-1)  # Eq 2.20

    # M_BT: alpha_BT about X at the pivot, then the offsets dx_BT, dz_BT (Eq 2.2)
    q = np.array([0.0, 0.0, geo.Z_T - geo.R_B if piv.alpha_BT == "tool-Z_T" else 0.0])
    R_bt = rotation(np.stack([p["alpha_BT"], zero, zero], axis=-1))
    t1 = q + _apply(R_bt, t - q) + np.stack([p["dx_BT"], zero, p["dz_BT"]], axis=-1)

    # E_B: B rotation about +Y (Eq 2.4), per angle
    cB, sB = np.cos(cmd.B), np.sin(cmd.B)
    E_B = np.zeros((len(cmd.B), 3, 3))
    E_B[:, 0, 0], E_B[:, 0, 2], E_B[:, 1, 1], E_B[:, 2, 0], E_B[:, 2, 2] = cB, sB, 1.0, -sB, cB
    t2 = np.swapaxes(t1 @ np.transpose(E_B, (0, 2, 1)), 0, 1)  # (n, k, 3)

    # M_XB (Eq 2.3)
    if piv.xb_angles == "slide-X_T-Z_T":
        pivot = np.array([geo.X_T, 0.0, geo.Z_T - geo.R_B])
    else:
        pivot = np.zeros(3)
    beta_in_head = p["beta_XB"] if piv.beta_XB == "b-centre" else zero
    R_xb = rotation(np.stack([p["alpha_XB"], beta_in_head, p["gamma_XB"]], axis=-1))
    t3 = pivot + _apply(R_xb, t2 - pivot)

    # travels with squareness (Eqs 2.5–2.9) about the frame or NC origin
    O = nc_origin(geo) if piv.origin == "nc" else np.zeros(3)
    R_xy = rotation(np.stack([zero, zero, p["gamma_XY"]], axis=-1))
    R_yz = rotation(np.stack([p["alpha_YZ"], p["beta_YZ"], zero], axis=-1))
    k = len(cmd.X)
    x_travel = np.zeros((k, 3))
    x_travel[:, 0] = cmd.X - O[0]
    y_travel = np.zeros((k, 3))
    y_travel[:, 1] = cmd.Y - O[1]
    z_travel = np.zeros((k, 3))
    z_travel[:, 2] = cmd.Z - O[2]
    inner = _apply(R_yz, y_travel + _apply(R_xy, x_travel + t3))
    if piv.beta_XB == "z-travel":
        R_zt = rotation(np.stack([zero, p["beta_XB"], zero], axis=-1))
        z_part = z_travel @ np.transpose(R_zt, (0, 2, 1))
    else:
        z_part = np.broadcast_to(z_travel, inner.shape)
    return O + z_part + inner


class CAxis:
    """The actual C axis of a mount: ``A(v) = R (v − h·e_z) + h·e_z + d`` (Eq 2.11 with its pivot height)."""

    def __init__(self, p: dict[str, np.ndarray], Z_C: float, piv: Pivots):
        zero = np.zeros_like(p["dx_CZ"])
        self.R = rotation(np.stack([p["alpha_CZ"], p["beta_CZ"], zero], axis=-1))
        self.h = np.array([0.0, 0.0, 2.0 * Z_C if piv.c_tilt_height == "2Z_C" else 0.0])
        self.d = np.stack([p["dx_CZ"], p["dy_CZ"], zero], axis=-1)

    def to_machine(self, v: np.ndarray) -> np.ndarray:
        """C-frame points ``(n,3)`` or ``(n,k,3)`` to machine frame."""
        d = self.d if v.ndim == 2 else self.d[:, None, :]
        return _apply(self.R, v - self.h) + self.h + d

    def to_table(self, w: np.ndarray) -> np.ndarray:
        """Machine-frame points ``(n,3)`` or ``(n,k,3)`` to the C frame (Eq 2.16)."""
        d = self.d if w.ndim == 2 else self.d[:, None, :]
        return _apply(np.transpose(self.R, (0, 2, 1)), w - d - self.h) + self.h


def w_ball(p: dict[str, np.ndarray], axis: CAxis, P0: np.ndarray, *, w_offset: np.ndarray,
           cmd: Commands) -> np.ndarray:
    """Actual W-ball centre ``(n, k, 3)``: placed at ``P0`` (n,3), offset by ``w_offset`` (n,3) in the C frame."""
    W_C = axis.to_table(P0) + w_offset  # Eq 2.21
    cC, sC = np.cos(cmd.C), np.sin(cmd.C)
    E_C = np.zeros((len(cmd.C), 3, 3))
    E_C[:, 0, 0], E_C[:, 0, 1], E_C[:, 1, 0], E_C[:, 1, 1], E_C[:, 2, 2] = cC, -sC, sC, cC, 1.0
    return axis.to_machine(np.swapaxes(W_C @ np.transpose(E_C, (0, 2, 1)), 0, 1))
