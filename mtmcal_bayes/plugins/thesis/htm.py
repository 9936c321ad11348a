"""Homogeneous-transform kinematic model of the ball-bar patterns (thesis Eqs 2.1–2.21, SPEC §3.2).

Spindle side (thesis Eq 2.10 with the T-ball offset of Eq 2.20)::

    T = E_Z M_YZ E_Y M_XY E_X M_XB E_B M_BT T_T,   T_T = (xT, yT, −(R_B + dRB) + zT)

Workpiece side (Eqs 2.13–2.16, 2.21): the W ball is placed once per mount at
the actual position P0 of the dummy sphere (true tool length, no ball offset,
B = 0, the commands of the mount's first run at zero angle), expressed in the
C-axis frame, offset by (xW, yW, zW), and turned with C::

    W(θ) = M_CZ E_C(θ) (M_CZ⁻¹ P0 + w),      ΔL = |T − W| − L_B

Rotations are exact (``expm([ε]×)``, Rodrigues' formula: :mod:`mtmcal_bayes.machines.rotations`, which the chain
shares).  This is the thesis' own model (its Eq 2.10 and pivots), the thesis plug-in's; on the thesis machine the
chain equals ``htm-literal`` to 1e-9 mm (``tests/test_kinematic.py``).
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

Everything is vectorised over the parameter batch (n) and the evaluation points (k): the points of
all runs and mount placements of a campaign go through the chain in one pass, each with its own
geometry (lever arms as arrays of shape (k,)) and nuisance terms (arrays (n, k)).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...machines.rotations import _apply, rotation
from .pattern_tables import Commands


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


def _rotate(angles: list[np.ndarray], v: np.ndarray) -> np.ndarray:
    """``v`` (n, k, 3) turned by the rotation vectors whose components are ``angles`` (each (n,) or 0);
    unchanged, exactly, where all are zero (the linear-axis squareness is often held at zero)."""
    n = v.shape[0]
    vec = np.stack([np.broadcast_to(np.asarray(a, dtype=float), (n,)) for a in angles], axis=-1)
    return v if not vec.any() else _apply(rotation(vec), v)


def _per_point(v, k: int) -> np.ndarray:
    """A geometry value as an array ``(k,)``."""
    return np.broadcast_to(np.asarray(v, dtype=float), (k,))


def _column(v) -> np.ndarray:
    """A parameter as ``(n, 1)`` (one value per draw) or ``(n, k)`` (one per point)."""
    v = np.asarray(v, dtype=float)
    return v[:, None] if v.ndim == 1 else v


def t_ball(p: dict[str, np.ndarray], geo: Geometry, cmd: Commands, piv: Pivots, *,
           dummy=False) -> np.ndarray:
    """Actual T-ball (or dummy-sphere) centre, shape ``(n, k, 3)``, mm.

    ``p`` maps parameter base names to arrays ``(n,)`` (internal units): the 13 deviations and
    the setup's ``xT, yT, zT, dRB``, which may also be ``(n, k)``, one per point.  ``geo``'s lever
    arms are scalars or ``(k,)``.  ``dummy`` (bool or ``(k,)``) marks the dummy sphere: true tool
    length, no ball offset.
    """
    n, k = len(p["dx_BT"]), len(cmd.B)
    R_B, Z_T, X_T, Z_C = (_per_point(v, k) for v in (geo.R_B, geo.Z_T, geo.X_T, geo.Z_C))
    real = ~np.broadcast_to(np.asarray(dummy, dtype=bool), (k,))
    t = np.empty((n, k, 3))  # Eq 2.20
    t[..., 0] = _column(p["xT"]) * real
    t[..., 1] = _column(p["yT"]) * real
    t[..., 2] = -(R_B + _column(p["dRB"])) + _column(p["zT"]) * real

    # M_BT: alpha_BT about X at the pivot, then the offsets dx_BT, dz_BT (Eq 2.2)
    q = np.zeros((k, 3))
    if piv.alpha_BT == "tool-Z_T":
        q[:, 2] = Z_T - R_B
    t1 = q + _rotate([p["alpha_BT"], 0, 0], t - q)
    t1[..., 0] += _column(p["dx_BT"])
    t1[..., 2] += _column(p["dz_BT"])

    # E_B: B rotation about +Y (Eq 2.4), per point
    cB, sB = np.cos(cmd.B), np.sin(cmd.B)
    t2 = np.empty_like(t1)
    t2[..., 0] = cB * t1[..., 0] + sB * t1[..., 2]
    t2[..., 1] = t1[..., 1]
    t2[..., 2] = cB * t1[..., 2] - sB * t1[..., 0]

    # M_XB (Eq 2.3)
    pivot = np.zeros((k, 3))
    if piv.xb_angles == "slide-X_T-Z_T":
        pivot[:, 0], pivot[:, 2] = X_T, Z_T - R_B
    beta_in_head = p["beta_XB"] if piv.beta_XB == "b-centre" else 0
    t3 = pivot + _rotate([p["alpha_XB"], beta_in_head, p["gamma_XB"]], t2 - pivot)

    # travels with squareness (Eqs 2.5–2.9) about the frame or NC origin
    O = np.zeros((k, 3))
    if piv.origin == "nc":
        O[:, 0], O[:, 2] = X_T, Z_C + R_B + Z_T  # nc_origin, per point
    x_travel = np.zeros((k, 3))
    x_travel[:, 0] = cmd.X - O[:, 0]
    y_travel = np.zeros((k, 3))
    y_travel[:, 1] = cmd.Y - O[:, 1]
    z_travel = np.zeros((k, 3))
    z_travel[:, 2] = cmd.Z - O[:, 2]
    inner = _rotate([p["alpha_YZ"], p["beta_YZ"], 0], y_travel + _rotate([0, 0, p["gamma_XY"]], x_travel + t3))
    if piv.beta_XB == "z-travel":
        z_part = _rotate([0, p["beta_XB"], 0], np.broadcast_to(z_travel, inner.shape))
    else:
        z_part = z_travel
    return O + z_part + inner


class CAxis:
    """The actual C axis of a mount: ``A(v) = R (v − h·e_z) + h·e_z + d`` (Eq 2.11 with its pivot height).

    ``Z_C`` is a scalar or ``(k,)``, one per point (points of several mounts in one pass).
    """

    def __init__(self, p: dict[str, np.ndarray], Z_C, piv: Pivots):
        zero = np.zeros_like(p["dx_CZ"])
        self.R = rotation(np.stack([p["alpha_CZ"], p["beta_CZ"], zero], axis=-1))
        height = 2.0 * np.asarray(Z_C, dtype=float) if piv.c_tilt_height == "2Z_C" else np.zeros(np.shape(Z_C))
        self.h = np.zeros(np.shape(height) + (3,))
        self.h[..., 2] = height
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
    """Actual W-ball centre ``(n, k, 3)``: placed at ``P0`` (n,3) or (n,k,3), offset by ``w_offset`` (same shape)
    in the C frame, turned by C."""
    W_C = axis.to_table(P0) + w_offset  # Eq 2.21
    if W_C.ndim == 2:
        W_C = np.broadcast_to(W_C[:, None, :], (len(W_C), len(cmd.C), 3))
    cC, sC = np.cos(cmd.C), np.sin(cmd.C)
    turned = np.empty(W_C.shape)
    turned[..., 0] = cC * W_C[..., 0] - sC * W_C[..., 1]
    turned[..., 1] = sC * W_C[..., 0] + cC * W_C[..., 1]
    turned[..., 2] = W_C[..., 2]
    return axis.to_machine(turned)
