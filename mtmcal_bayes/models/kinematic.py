"""The kinematic forward models ``htm-literal`` and ``htm-thesis`` for the runs of a campaign.

Each run is simulated as a ΔL trace over its angle grid and reduced to
eccentricities by the same least-squares extractor that reads measured
traces.  Simulated runs have no dynamics, so CW and CCW traces are identical
and one sweep stands for their average.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import MtmcalError
from ..observations import Observations
from ..parameters import (
    DEVIATIONS,
    MOUNT_NUISANCE,
    SETUP_NUISANCE,
    ParameterSpace,
    nuisance_name,
)
from ..patterns import (
    B_PATTERNS,
    COMPONENTS,
    Commands,
    fit_eccentricity,
    mount_conflict,
    pattern_commands,
)
from .htm import PIVOTS, CAxis, Geometry, Pivots, t_ball, w_ball


@dataclass(frozen=True)
class _RunPlan:
    pattern: str
    setup: str
    mount: str
    geometry: Geometry
    commands: Commands


class HTMModel:
    """Nonlinear ball-bar model of a campaign: parameter batch ``(n, p)`` -> eccentricities ``(n, m)``.

    Parameters
    ----------
    campaign : Campaign
    pivots : Pivots or name (``"htm-literal"``, ``"htm-thesis"``)
    space : ParameterSpace, optional
        Parameters absent from ``space`` are held at zero.
    b_angles_deg, c_angles_deg : angle grids (default 0–90° by 1°, 0–355° by 5°)
    """

    def __init__(self, campaign, pivots: Pivots | str = "htm-thesis", space: ParameterSpace | None = None, *,
                 b_angles_deg=None, c_angles_deg=None):
        self.pivots = PIVOTS[pivots] if isinstance(pivots, str) else pivots
        self.name = self.pivots.name
        self.campaign = campaign
        self.space = space or ParameterSpace.for_campaign(campaign)
        self.observations = Observations.from_campaign(campaign)
        bb = campaign.ballbar
        geometry = getattr(bb, "cr_geometry", "RC-LB")
        for r in bb.runs:  # campaigns built in Python skip the loader's check
            if mount_conflict(r.pattern, r.mount, bb.mounts[r.mount].R_C):
                raise MtmcalError(f"run {r.label}: pattern {r.pattern} measures with the W ball on the C axis "
                                  f"(thesis Table 2.2), but mount {r.mount!r} has R_C = {bb.mounts[r.mount].R_C:g} mm")

        def plan(pattern, setup_id, mount_id, angles=None):
            s, m = bb.setups[setup_id], bb.mounts[mount_id]
            geo = Geometry(s.R_B, s.Z_T, s.X_T, m.Z_C, m.R_C)
            if angles is None:
                angles = b_angles_deg if pattern in B_PATTERNS else c_angles_deg
            cmd = pattern_commands(pattern, R_B=s.R_B, Z_C=m.Z_C, R_C=m.R_C, L_B=bb.length, angles_deg=angles,
                                   cr_geometry=geometry)
            return _RunPlan(pattern, setup_id, mount_id, geo, cmd)

        self.runs = [plan(r.pattern, r.setup, r.mount) for r in bb.runs]
        # the dummy sphere of each mount: first run on it, zero angle, X = 0 (B) or R_C (C), Z = Z_C + R_B
        self.placements: dict[str, _RunPlan] = {}
        for r in bb.runs:
            if r.mount not in self.placements:
                s, m = bb.setups[r.setup], bb.mounts[r.mount]
                x0 = 0.0 if r.pattern in B_PATTERNS else m.R_C
                cmd = Commands(*(np.array([v]) for v in (x0, 0.0, m.Z_C + s.R_B, 0.0, 0.0, 0.0)))
                self.placements[r.mount] = _RunPlan(r.pattern, r.setup, r.mount,
                                                    Geometry(s.R_B, s.Z_T, s.X_T, m.Z_C, m.R_C), cmd)
        comp_index = {(k.run, k.component): i for i, k in enumerate(self.observations.keys)}
        self._columns = [[(comp_index.get((i, c)), j) for j, c in enumerate(COMPONENTS[r.pattern])]
                         for i, r in enumerate(bb.runs)]

    # ------------------------------------------------------------------ parameters
    def _params(self, theta: np.ndarray, setup: str, mount: str | None = None) -> dict[str, np.ndarray]:
        n = theta.shape[0]
        col = self.space.index

        def get(name):
            try:
                return theta[:, col(name)]
            except KeyError:
                return np.zeros(n)

        p = {d: get(d) for d in DEVIATIONS}
        p.update({b: get(nuisance_name(b, setup)) for b in SETUP_NUISANCE})
        if mount is not None:
            p.update({b: get(nuisance_name(b, mount)) for b in MOUNT_NUISANCE})
        return p

    # ------------------------------------------------------------------ simulation
    def traces(self, theta: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """ΔL traces of every run: list of ``(psi (k,), dL (n, k))`` in rad and mm."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        placed = {}
        for mount, pl in self.placements.items():
            p = self._params(theta, pl.setup)
            placed[mount] = t_ball(p, pl.geometry, pl.commands, self.pivots, dummy=True)[:, 0, :]
        out = []
        for run in self.runs:
            p = self._params(theta, run.setup, run.mount)
            T = t_ball(p, run.geometry, run.commands, self.pivots)
            axis = CAxis(p, run.geometry.Z_C, self.pivots)
            w_off = np.stack([p["xW"], p["yW"], p["zW"]], axis=-1)
            W = w_ball(p, axis, placed[run.mount], w_offset=w_off, cmd=run.commands)
            dL = np.linalg.norm(T - W, axis=-1) - self.campaign.ballbar.length
            out.append((run.commands.psi, dL))
        return out

    def eccentricities(self, theta: np.ndarray):
        """Per run, the :class:`~mtmcal_bayes.patterns.EccentricityFit` of its simulated trace."""
        return [fit_eccentricity(run.pattern, psi, dL) for run, (psi, dL) in zip(self.runs, self.traces(theta))]

    def predict(self, theta: np.ndarray) -> np.ndarray:
        """Predicted eccentricities, mm: ``(n, p)`` -> ``(n, m)``; ``(p,)`` -> ``(m,)``."""
        theta = np.asarray(theta, dtype=float)
        single = theta.ndim == 1
        theta2 = np.atleast_2d(theta)
        out = np.empty((theta2.shape[0], len(self.observations)))
        for fit, cols in zip(self.eccentricities(theta2), self._columns):
            for i, j in cols:
                if i is not None:
                    out[:, i] = fit.coef[:, 1 + j]
        return out[0] if single else out

    __call__ = predict


def jacobian(model, theta0: np.ndarray | None = None, steps: np.ndarray | None = None) -> np.ndarray:
    """Central finite-difference Jacobian ``(m, p)`` of ``model.predict`` at ``theta0`` (default zero).

    Default steps: 1″ for angles, 1 µm for lengths; all 2p evaluations in one batch.
    """
    p = len(model.space)
    theta0 = np.zeros(p) if theta0 is None else np.asarray(theta0, float)
    h = model.space.display_scale() if steps is None else np.asarray(steps, float)
    batch = np.concatenate([theta0 + np.diag(h), theta0 - np.diag(h)])
    pred = model.predict(batch)
    return ((pred[:p] - pred[p:]) / (2 * h)[:, None]).T
