"""The kinematic forward models ``htm-literal`` and ``htm-thesis`` for the runs of a campaign.

Each run is simulated as a ΔL trace over its angle grid and reduced to
eccentricities by the same least-squares extractor that reads measured
traces.  Simulated runs have no dynamics, so CW and CCW traces are identical
and one sweep stands for their average.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import MtmcalError
from ...observations import Observations
from ...parameters import (
    DEVIATIONS,
    MOUNT_NUISANCE,
    SETUP_NUISANCE,
    ParameterSpace,
    nuisance_name,
)
from ...patterns import B_PATTERNS, COMPONENTS, fit_eccentricity, mount_conflict
from .pattern_tables import Commands, pattern_commands
from .htm import PIVOTS, CAxis, Geometry, Pivots, t_ball, w_ball

#: rows of a parameter batch evaluated at once (memory: a few MB per temporary)
CHUNK = 256


@dataclass(frozen=True)
class _Points:
    """The evaluation points of a model in one table (k points): commands, lever arms, dummy-sphere flags,
    the point of each one's mount placement, the slices of the runs, and the parameter columns to read
    (−1: absent, zero)."""

    cmd: Commands
    geometry: Geometry
    dummy: np.ndarray
    placement: np.ndarray
    runs: list
    deviation_cols: dict
    setup_cols: dict
    mount_cols: dict


@dataclass(frozen=True)
class _RunPlan:
    pattern: str
    setup: str
    mount: str
    geometry: Geometry
    commands: Commands


def placing_runs(ballbar) -> dict[str, int]:
    """The run that places each mount's W ball (its dummy sphere), by mount: the first run on it.  Every run on a
    mount depends on that run's setup and pattern, so the runs of a mount are not simulated without it."""
    first: dict[str, int] = {}
    for i, run in enumerate(ballbar.runs):
        first.setdefault(run.mount, i)
    return first


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
                 b_angles_deg=None, c_angles_deg=None, observations: Observations | None = None):
        self.pivots = PIVOTS[pivots] if isinstance(pivots, str) else pivots
        self.name = self.pivots.name
        self.campaign = campaign
        self.space = space or ParameterSpace.for_campaign(campaign)
        self.observations = observations or Observations.from_campaign(campaign)
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
        for mount, i in placing_runs(bb).items():
            r = bb.runs[i]
            s, m = bb.setups[r.setup], bb.mounts[mount]
            x0 = 0.0 if r.pattern in B_PATTERNS else m.R_C
            cmd = Commands(*(np.array([v]) for v in (x0, 0.0, m.Z_C + s.R_B, 0.0, 0.0, 0.0)))
            self.placements[mount] = _RunPlan(r.pattern, r.setup, mount, Geometry(s.R_B, s.Z_T, s.X_T, m.Z_C, m.R_C),
                                              cmd)
        comp_index = {(k.run, k.component): i for i, k in enumerate(self.observations.keys)}
        self._columns = [[(comp_index.get((i, c)), j) for j, c in enumerate(COMPONENTS[r.pattern])]
                         for i, r in enumerate(bb.runs)]
        self._points = None

    def replace_commands(self, run: int, commands: Commands) -> None:
        """Simulate run ``run`` with other commands (e.g. a compensated program) from now on."""
        self.runs[run] = _RunPlan(self.runs[run].pattern, self.runs[run].setup, self.runs[run].mount,
                                  self.runs[run].geometry, commands)
        self._points = None

    # ------------------------------------------------------------------ the evaluation points
    def _point_table(self) -> _Points:
        """Every evaluation point of every run, and one per mount for its dummy sphere, in one table."""
        if self._points is None:
            plans = list(self.placements.values()) + self.runs
            sizes = [len(pl.commands.B) for pl in plans]
            starts = np.concatenate([[0], np.cumsum(sizes)])
            cat = lambda f: np.concatenate([np.broadcast_to(f(pl), (n,)) for pl, n in zip(plans, sizes)])  # noqa: E731
            cmd = Commands(*(cat(lambda pl, a=a: getattr(pl.commands, a)) for a in ("X", "Y", "Z", "B", "C", "psi")))
            geo = Geometry(*(cat(lambda pl, a=a: getattr(pl.geometry, a)) for a in ("R_B", "Z_T", "X_T", "Z_C", "R_C")))
            n_place = len(self.placements)
            place_index = {m: starts[i] for i, m in enumerate(self.placements)}
            col = {name: i for i, name in enumerate(self.space.names)}  # absent parameters: column -1, a zero
            setup_cols = {b: cat(lambda pl, b=b: col.get(nuisance_name(b, pl.setup), -1)).astype(int)
                          for b in SETUP_NUISANCE}
            mount_cols = {b: cat(lambda pl, b=b: col.get(nuisance_name(b, pl.mount), -1)).astype(int)
                          for b in MOUNT_NUISANCE}
            self._points = _Points(
                cmd=cmd, geometry=geo, dummy=np.arange(starts[-1]) < starts[n_place],
                placement=cat(lambda pl: place_index[pl.mount]).astype(int),
                runs=[slice(starts[n_place + i], starts[n_place + i + 1]) for i in range(len(self.runs))],
                deviation_cols={d: col.get(d, -1) for d in DEVIATIONS}, setup_cols=setup_cols, mount_cols=mount_cols)
        return self._points

    # ------------------------------------------------------------------ simulation
    def _dL(self, theta: np.ndarray) -> np.ndarray:
        """ΔL ``(n, k)`` mm at every point of the table, for a batch ``(n, p)``."""
        pts = self._point_table()
        ext = np.concatenate([theta, np.zeros((len(theta), 1))], axis=1)  # column -1 holds zero
        p = {d: ext[:, c] for d, c in pts.deviation_cols.items()}
        p.update({b: ext[:, c] for b, c in pts.setup_cols.items()})  # (n, k)
        T = t_ball(p, pts.geometry, pts.cmd, self.pivots, dummy=pts.dummy)
        axis = CAxis(p, pts.geometry.Z_C, self.pivots)
        w_off = np.stack([ext[:, pts.mount_cols[b]] for b in MOUNT_NUISANCE], axis=-1)  # (n, k, 3)
        W = w_ball(p, axis, T[:, pts.placement, :], w_offset=w_off, cmd=pts.cmd)
        diff = T - W
        return np.sqrt(np.einsum("nki,nki->nk", diff, diff)) - self.campaign.ballbar.length

    def traces(self, theta: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """ΔL traces of every run: list of ``(psi (k,), dL (n, k))`` in rad and mm.

        Batches are evaluated :data:`CHUNK` rows at a time: the chain's temporaries are (rows, k, 3)
        arrays, and a few thousand rows at once would take hundreds of MB for no gain in speed.
        """
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        dL = np.concatenate([self._dL(theta[i:i + CHUNK]) for i in range(0, len(theta), CHUNK)]) \
            if len(theta) > CHUNK else self._dL(theta)
        return [(run.commands.psi, dL[:, sl]) for run, sl in zip(self.runs, self._point_table().runs)]

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
