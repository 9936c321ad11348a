"""The kinematic forward models ``htm-literal`` and ``htm-thesis``: the engine's ball-bar model
(:class:`~mtmcal_bayes.models.ballbar.BallbarModel`) with the thesis' Eq 2.10 and its pivots as the kernel.

The engine's model places the W balls, lays out the runs' points (a thesis-format run's commands are those of
Tables 2.2/2.3 as printed, which its campaign states, :func:`.translation.table_commands`; the engine's patterns give
them to rounding, ``tests/test_chain.py``), reads the parameter columns and fits each simulated trace;
:class:`PivotsKernel` turns the commands into bar lengths through :func:`~.htm.t_ball` and :func:`~.htm.w_ball`.
Simulated runs have no dynamics, so CW and CCW traces are identical and one sweep stands for their average.
"""

from __future__ import annotations

import numpy as np

from ...errors import MtmcalError
from ...models.ballbar import BallbarModel, BallbarPoints
from ...observations import Observations
from ...parameters import DEVIATIONS, ParameterSpace
from ...patterns import B_PATTERNS, PATTERNS, mount_conflict
from .htm import PIVOTS, CAxis, Geometry, Pivots, t_ball, w_ball
from .pattern_tables import Commands
from .translation import translated


class PivotsKernel:
    """The thesis' kernel: the bar length ``|T − W|`` of Eq 2.10 with the angular deviations pivoting as ``pivots``
    says (:class:`~.htm.Pivots`), each point with its setup's and mount's lever arms (Z_T, X_T; Z_C, R_C).

    The ``integrex-i200`` description's frame is the thesis' model frame (the C-axis centreline at the table
    surface; the commands the B-axis centre's position), so the model's commands X, Y, Z, B, C are the kernel's as
    they stand; the NC origin its pivots refer to is at (X_T, 0, Z_C + R_B + Z_T) (:func:`~.htm.nc_origin`).
    """

    complex_step = False

    def __init__(self, ballbar, pivots: Pivots):
        self.pivots = pivots
        self.name = pivots.name
        self.setups, self.mounts = ballbar.setups, ballbar.mounts
        self._arms: tuple[BallbarPoints, Geometry] | None = None

    def geometry(self, setup: str, mount: str) -> Geometry:
        """The lever arms of a run of ``setup`` on ``mount``, mm."""
        s, m = self.setups[setup], self.mounts[mount]
        return Geometry(s.R_B, s.Z_T, s.X_T, m.Z_C, m.R_C)

    def _geometry(self, pts: BallbarPoints) -> Geometry:
        """The lever arms of every point, each (k,) mm (kept for the table they were read from)."""
        if self._arms is None or self._arms[0] is not pts:
            s = [self.setups[i] for i in pts.setup]
            m = [self.mounts[i] for i in pts.mount]
            self._arms = (pts, Geometry(pts.length, _arm(s, "Z_T"), _arm(s, "X_T"), _arm(m, "Z_C"), _arm(m, "R_C")))
        return self._arms[1]

    def lengths(self, pts: BallbarPoints, dev: dict, setup_terms: dict, w_off: np.ndarray) -> np.ndarray:
        """``|T − W|`` ``(n, k)`` mm (the deviations the space lacks held at zero)."""
        geo = self._geometry(pts)
        q = pts.q
        cmd = Commands(q["X"], q["Y"], q["Z"], q["B"], q["C"], None)  # no polar angle: that is the fit's
        zero = np.zeros(len(w_off))
        p = {d: dev.get(d, zero) for d in DEVIATIONS}
        p.update(setup_terms)
        T = t_ball(p, geo, cmd, self.pivots, dummy=pts.dummy)
        W = w_ball(p, CAxis(p, geo.Z_C, self.pivots), T[:, pts.placement, :], w_offset=w_off, cmd=cmd)
        diff = T - W
        return np.sqrt(np.einsum("nki,nki->nk", diff, diff))


def _arm(owners: list, name: str) -> np.ndarray:
    """The lever arm ``name`` (k,) mm of each point's setup or mount."""
    return np.array([getattr(o, name) for o in owners], dtype=float)


def HTMModel(campaign, pivots: Pivots | str = "htm-thesis", space: ParameterSpace | None = None, *,
             b_angles_deg=None, c_angles_deg=None, observations: Observations | None = None) -> BallbarModel:
    """The ball-bar model ``htm-literal`` or ``htm-thesis`` of a thesis-format campaign: parameter batch
    ``(n, p)`` -> eccentricities ``(n, m)``.

    Parameters
    ----------
    campaign : Campaign
    pivots : Pivots or name (``"htm-literal"``, ``"htm-thesis"``)
    space : ParameterSpace, optional
        Parameters absent from ``space`` are held at zero.
    b_angles_deg, c_angles_deg : angle grids (default 0–90° by 1°, 0–355° by 5°)
    """
    pivots = PIVOTS[pivots] if isinstance(pivots, str) else pivots
    bb = campaign.ballbar
    for r in bb.runs:  # campaigns built in Python skip the loader's check
        if mount_conflict(r.pattern, r.mount, bb.mounts[r.mount].R_C):
            raise MtmcalError(f"run {r.label}: pattern {r.pattern} measures with the W ball on the C axis "
                              f"(thesis Table 2.2), but mount {r.mount!r} has R_C = {bb.mounts[r.mount].R_C:g} mm")
    engine = translated(campaign)
    for p in PATTERNS:
        grid = b_angles_deg if p in B_PATTERNS else c_angles_deg
        if grid is not None:
            engine.ballbar.pattern_arcs[p] = np.asarray(grid, dtype=float)
    return BallbarModel(engine, space or ParameterSpace.for_campaign(campaign), kernel=PivotsKernel(engine.ballbar, pivots),
                        observations=observations or Observations.from_campaign(campaign))
