"""Touch-probe geometry: least-squares sphere fit of probed points, with the covariance of its centre."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import MtmcalError


@dataclass
class SphereFit:
    """Result of :func:`fit_sphere` (mm).

    ``centre`` (3,); ``radius`` of the probed sphere (fitted radius of the
    stylus-centre points minus the stylus-ball radius); ``residuals`` (n,)
    signed radial residuals; ``rms`` their root mean square; ``centre_cov`` (3, 3) mm², the
    covariance of the centre from the residual scatter (``s² (JᵀJ)⁻¹`` of the geometric fit over
    centre and radius, ``s²`` = residual sum of squares / (n − 4)); NaN with only four points.
    """

    centre: np.ndarray
    radius: float
    fitted_radius: float
    stylus_radius: float
    residuals: np.ndarray
    centre_cov: np.ndarray | None = None

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.residuals**2)))


def fit_sphere(points: np.ndarray, stylus_radius: float = 0.0) -> SphereFit:
    """Geometric least-squares sphere through ``points`` of shape ``(n, 3)``, mm.

    An algebraic fit (linear in centre and ``r² − |c|²``) starts a
    Levenberg–Marquardt refinement of the orthogonal distances.  The points
    are taken as stylus-ball centres at contact: the centre is unchanged by
    ``stylus_radius`` and the sphere's radius is the fitted one minus it.
    Raises :class:`MtmcalError` for fewer than four points or points that do
    not determine a sphere (coplanar, coincident).
    """
    P = np.asarray(points, dtype=float)
    if P.ndim != 2 or P.shape[1] != 3 or len(P) < 4:
        raise MtmcalError(f"a sphere fit needs at least 4 points in 3-D, got {len(P)}")
    shift = P.mean(axis=0)
    Q = P - shift  # centred for conditioning
    A = np.c_[2 * Q, np.ones(len(Q))]
    with np.errstate(over="ignore", invalid="ignore"):
        b = (Q**2).sum(axis=1)
    if not (np.isfinite(P).all() and np.isfinite(b).all()):
        raise MtmcalError("coordinates too large for a sphere fit (their squares overflow)")
    sol, _, rank, sv = np.linalg.lstsq(A, b, rcond=None)
    if rank < 4 or sv[-1] < 1e-9 * sv[0]:
        raise MtmcalError("the points do not determine a sphere (coplanar or coincident)")
    c0 = sol[:3]
    r0 = np.sqrt(max(sol[3] + c0 @ c0, 0.0))

    def resid(x):
        return np.linalg.norm(Q - x[:3], axis=1) - x[3]

    from scipy.optimize import (
        least_squares,  # here: the package imports quickly for commands that never fit
    )

    res = least_squares(resid, np.r_[c0, r0], method="lm", xtol=1e-15, ftol=1e-15)
    centre, r = res.x[:3] + shift, abs(res.x[3])
    if stylus_radius < 0 or stylus_radius >= r:
        raise MtmcalError(f"stylus radius {stylus_radius:g} mm must be >= 0 and below the fitted radius {r:.4f} mm")
    residuals = resid(res.x)
    dof = len(P) - 4
    cov = np.full((3, 3), np.nan)
    if dof > 0:
        J = res.jac
        cov = (residuals @ residuals / dof) * np.linalg.pinv(J.T @ J)[:3, :3]
    return SphereFit(centre, r - stylus_radius, r, stylus_radius, residuals, 0.5 * (cov + cov.T))
