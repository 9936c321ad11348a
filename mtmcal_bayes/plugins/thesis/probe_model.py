"""Touch-probe readings through the kinematic chain (SPEC §12): parameter batches ``(n, p)`` -> ``(n, m)``.

A reading is the commanded tool point (X, Y, Z, in the reading frame) at which the actual stylus-ball
centre coincides with the actual sphere centre, at the indexed B and C.  The stylus is a tool of the
chain of :func:`~.htm.t_ball` with its own nuisance terms: centre offset ``xS, yS`` (like ``xT, yT``)
and length error ``dRS − rS`` (tool-length error minus the effective-radius error, which moves a
probed centre towards the spindle).  The programmed length ``R_B`` runs to the stylus-ball centre, or
to its tip when the campaign gives ``ball_radius_mm``.  The chain is affine in the commands, so the
inverse kinematics is exact: the tool point at the nominal command and at unit steps of X, Y, Z gives
the 3 × 3 map, and one batched solve gives the command.

Spheres:

* C-axis run: a sphere on the table at radius ``R_C`` and height ``Z_C`` (C frame), placed with the
  nuisance offset ``xP, yP``, turned by C and carried by the actual C axis (:class:`~.htm.CAxis`).
  Readings are in machine coordinates with the C axis at ``axis_xy`` (``datum = "machine"``), or in a
  frame zeroed on the sphere (``datum = "first"``: a broad datum nuisance ``xD, yD``); the Z datum is
  never stated, so ``zD`` is always a broad nuisance.
* B-axis run: a fixed sphere probed at each B angle with each stylus; where it is (in the reading
  frame) is the broad nuisance ``xD, yD, zD``: only differences between indexed positions inform.

Lever arms of the chain for a stylus: ``R_B`` its centre length, ``Z_T`` = (R_B + Z_T of the campaign's
primary ball-bar setup) − R_B (R_B + Z_T is a dimension of the spindle head: 468.68 and 468.71 mm for
the thesis' two setups), ``X_T`` of the B-axis run (else of the primary setup), ``Z_C`` the sphere's
height.

Observations are readings minus their nominal (all deviations and nuisance terms zero), in the
frame of each centre's fit covariance where it has one (see :class:`ProbeLayout`), so every model
predicts zero at zero and the ``linear`` model is a design matrix: the Jacobian of the ``htm-thesis``
probe model at zero, like the ball-bar rows the thesis gives no relation for.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...errors import InputError
from ...observations import ProbeKey, ProbeObservations
from ...parameters import (
    DEVIATIONS,
    PROBE_NUISANCE,
    STYLUS_NUISANCE,
    ParameterSpace,
    nuisance_name,
)
from .pattern_tables import Commands
from .htm import PIVOTS, CAxis, Geometry, Pivots, t_ball

COMPONENTS = ("X", "Y", "Z")


@dataclass(frozen=True)
class ProbePosition:
    """One indexed position: run, stylus owner, B and C (rad), programmed length and ball radius (mm)."""

    run: str
    stylus: str
    angle_deg: float
    B: float
    C: float
    length: float
    ball_radius: float


class ProbeLayout:
    """The indexed positions of a campaign's probe runs, their lever arms, nominal frame and observations.

    Raises :class:`InputError` (naming the campaign and key) for probe data the likelihood cannot use.
    """

    def __init__(self, campaign):
        probe = campaign.probe
        src = campaign.source
        if probe is None or (probe.c_axis is None and (probe.b_axis is None or not probe.b_axis.styli)):
            raise InputError(src, "probe", "no touch-probe readings ([probe.c_axis] or [probe.b_axis.styli])")
        if probe.repeatability is None:
            raise InputError(src, "probe.repeatability_um", "missing: the probe's repeatability is its noise")
        primary = campaign.primary_setup()
        head = primary.R_B + primary.Z_T
        b, c = probe.b_axis, probe.c_axis
        X_T = b.X_T if b is not None else primary.X_T
        positions, geos, runs = [], [], []
        if (gap := campaign.probe_gap()) is not None:
            raise gap.error(src)
        if c is not None:
            st = b.styli[c.stylus] if c.stylus else None
            length, rb = (st.R_B, st.ball_radius) if st else (c.R_B, c.ball_radius)
            owner = probe.stylus_of_c_run()
            for a in c.angles_deg:
                positions.append(ProbePosition("c_axis", owner, float(a), 0.0, np.radians(a), length, rb))
                geos.append((length - rb, head - (length - rb), X_T, c.Z_C, c.R_C))
            runs.append(("c_axis", owner, c.centres, c.centre_cov))
        if b is not None:
            Z_sphere = b.Z_C if b.Z_C is not None else (c.Z_C if c is not None else campaign.mount_for("BX").Z_C)
            for s in b.styli.values():
                for a in b.angles_deg:
                    positions.append(ProbePosition("b_axis", s.id, float(a), np.radians(a), 0.0, s.R_B, s.ball_radius))
                    geos.append((s.R_B - s.ball_radius, head - (s.R_B - s.ball_radius), X_T, Z_sphere, 0.0))
                runs.append(("b_axis", s.id, s.centres, s.centre_cov))
        self.campaign = campaign
        self.positions = positions
        self.geometry = Geometry(*(np.array(v) for v in zip(*geos)))
        self.B = np.array([p.B for p in positions])
        self.C = np.array([p.C for p in positions])
        self.length = np.array([p.length for p in positions])
        self.is_c = np.array([p.run == "c_axis" for p in positions])
        # readings: mean over repeats (k, 3), their variance (k, 3, 3) and the frame of each (k, 3, 3)
        mean, cov, n, fitted = [], [], [], []
        u2 = probe.repeatability**2
        for run, owner, centres, fit_cov in runs:
            r, a = centres.shape[:2]
            mean.append(centres.mean(axis=0))
            if fit_cov is not None:  # one fitted centre per position: its fit covariance plus the repeatability
                cov.append(fit_cov[0] + u2 * np.eye(3))
            else:  # the pooled scatter of the run's repeats (the repeatability when not repeated), plus it
                s2 = np.sum(np.var(centres, axis=0, ddof=1)) / (a * 3) if r > 1 else u2
                cov.append(np.broadcast_to((s2 / r + u2) * np.eye(3), (a, 3, 3)))
            n += [r] * a
            fitted += [fit_cov is not None] * a
        self.reading_mean = np.concatenate(mean)  # (k, 3) mm, reading frame
        cov = np.concatenate(cov)
        fitted = np.array(fitted)
        # fitted centres turned into the principal axes of their covariance, so the likelihood stays diagonal
        Q = np.broadcast_to(np.eye(3), cov.shape).copy()
        lam = np.diagonal(cov, axis1=1, axis2=2).copy()
        if fitted.any():
            lam[fitted], Q[fitted] = np.linalg.eigh(cov[fitted])
        self.rotation = Q  # (k, 3, 3): observation = Qᵀ (reading − nominal)
        zero = ProbeChain(self, PIVOTS["htm-thesis"]).readings({}, 1)[0]  # model frame, all terms zero
        self.frame = self._datum_frame(campaign, zero)  # (k, 3) model frame -> reading frame
        self.nominal = zero + self.frame  # (k, 3) nominal readings
        y = np.einsum("kji,kj->ki", Q, self.reading_mean - self.nominal)
        keys = [ProbeKey(p.run, p.stylus, p.angle_deg, f"u{j + 1}" if fitted[i] else COMPONENTS[j])
                for i, p in enumerate(positions) for j in range(3)]
        self.observations = ProbeObservations(tuple(keys), y.reshape(-1), lam.reshape(-1),
                                              np.repeat(np.array(n, dtype=int), 3))

    # ------------------------------------------------------------------ the reading frame
    def _datum_frame(self, campaign, zero: np.ndarray) -> np.ndarray:
        """Offset ``(k, 3)`` from the model frame to the reading frame, mm.

        The C-axis run's X, Y with ``datum = "machine"``: the C axis at ``axis_xy``.  Every other
        component: where the first reading of the run puts it (its datum nuisance, broad, is then
        centred at zero; the readings' absolute value carries no information there).
        """
        frame = np.zeros((len(self.positions), 3))
        c = campaign.probe.c_axis
        for run in ("c_axis", "b_axis"):
            idx = [i for i, p in enumerate(self.positions) if p.run == run]
            if not idx:
                continue
            frame[idx] = self.reading_mean[idx[0]] - zero[idx[0]]
            if run == "c_axis" and c.datum == "machine":
                frame[idx, :2] = c.axis_xy
        return frame


class ProbeChain:
    """The probe readings of a :class:`ProbeLayout` under one set of pivots, for parameter dicts."""

    def __init__(self, layout: ProbeLayout, pivots: Pivots):
        self.layout, self.pivots = layout, pivots

    def readings(self, p: dict[str, np.ndarray], n: int) -> np.ndarray:
        """Readings ``(n, k, 3)`` in the model frame (the reading frame less :attr:`ProbeLayout.frame`), mm.

        ``p`` maps deviation names to ``(n,)`` and the tool/sphere terms ``xS, yS, dRS, rS, xP, yP,
        xD, yD, zD`` to ``(n, k)`` (one per position); absent entries are zero.
        """
        L = self.layout
        k = len(L.positions)
        zeros = np.zeros((n, k))
        get = lambda name, shape: p.get(name, np.zeros(shape))  # noqa: E731
        dev = {d: get(d, n) for d in DEVIATIONS}
        g = L.geometry
        # the actual sphere centre, model frame (n, k, 3)
        S = np.zeros((n, k, 3))
        S[..., 2] = g.Z_C
        if L.is_c.any():
            x0 = g.R_C + get("xP", (n, k))
            y0 = get("yP", (n, k))
            cC, sC = np.cos(L.C), np.sin(L.C)
            turned = np.stack([cC * x0 - sC * y0, sC * x0 + cC * y0, np.broadcast_to(g.Z_C, (n, k))], axis=-1)
            S_c = CAxis(dev, g.Z_C, self.pivots).to_machine(turned)
            S = np.where(L.is_c[None, :, None], S_c, S)
        # the stylus tool point at the nominal command and at unit steps of X, Y, Z (affine in the command)
        tool = {**dev, "xT": get("xS", (n, k)), "yT": get("yS", (n, k)), "zT": zeros,
                "dRB": get("dRS", (n, k)) - get("rS", (n, k))}
        nominal_S = np.zeros((k, 3))
        nominal_S[:, 2] = g.Z_C
        nominal_S[L.is_c, 0] = g.R_C[L.is_c] * np.cos(L.C[L.is_c])
        nominal_S[L.is_c, 1] = g.R_C[L.is_c] * np.sin(L.C[L.is_c])
        down = np.stack([-np.sin(L.B), np.zeros(k), -np.cos(L.B)], axis=-1)  # R(B)·(0, 0, −1)
        cmd0 = nominal_S - down * g.R_B[:, None]
        steps = np.concatenate([cmd0, cmd0 + [1.0, 0, 0], cmd0 + [0, 1.0, 0], cmd0 + [0, 0, 1.0]])
        tile = lambda a: np.tile(a, 4)  # noqa: E731
        cmd = Commands(steps[:, 0], steps[:, 1], steps[:, 2], tile(L.B), tile(L.C), np.zeros(4 * k))
        geo4 = Geometry(*(tile(v) for v in (g.R_B, g.Z_T, g.X_T, g.Z_C, g.R_C)))
        p4 = {name: (np.tile(v, (1, 4)) if np.ndim(v) == 2 else v) for name, v in tool.items()}
        T = t_ball(p4, geo4, cmd, self.pivots).reshape(n, 4, k, 3)
        M = np.stack([T[:, 1] - T[:, 0], T[:, 2] - T[:, 0], T[:, 3] - T[:, 0]], axis=-1)  # (n, k, 3, 3)
        command = cmd0 + np.linalg.solve(M, (S - T[:, 0])[..., None])[..., 0]
        datum = np.stack([get(b, (n, k)) for b in ("xD", "yD", "zD")], axis=-1)
        return command + down * L.length[:, None] + datum


class ProbeModel:
    """Touch-probe readings of a campaign under a kinematic model: ``(n, p)`` -> ``(n, m)``, m = 3 per position.

    Parameters
    ----------
    campaign : Campaign with ``[probe]`` readings
    pivots : ``"htm-literal"``, ``"htm-thesis"`` or a :class:`~.htm.Pivots`
    space : ParameterSpace (default: the deviations and the probe's nuisance terms)
    """

    def __init__(self, campaign, pivots: Pivots | str = "htm-thesis", space: ParameterSpace | None = None,
                 layout: ProbeLayout | None = None):
        self.pivots = PIVOTS[pivots] if isinstance(pivots, str) else pivots
        self.name = self.pivots.name
        self.campaign = campaign
        self.layout = layout or ProbeLayout(campaign)
        self.space = space or ParameterSpace.for_campaign(campaign, data="probe")
        self.observations = self.layout.observations
        self._chain = ProbeChain(self.layout, self.pivots)
        col = {name: i for i, name in enumerate(self.space.names)}
        pos = self.layout.positions
        self._dev_cols = {d: col[d] for d in DEVIATIONS if d in col}
        owner = lambda b, q: q.stylus if b in STYLUS_NUISANCE else q.run  # noqa: E731  (sphere terms: the run's)
        self._point_cols = {b: np.array([col.get(nuisance_name(b, owner(b, q)), -1) for q in pos], dtype=int)
                            for b in PROBE_NUISANCE}

    def readings(self, theta: np.ndarray) -> np.ndarray:
        """Readings ``(n, k, 3)`` in the reading frame, mm, for a batch ``(n, p)``."""
        theta = np.atleast_2d(np.asarray(theta, dtype=float))
        ext = np.concatenate([theta, np.zeros((len(theta), 1))], axis=1)  # column -1 holds zero
        p = {d: ext[:, c] for d, c in self._dev_cols.items()}
        p.update({b: ext[:, c] for b, c in self._point_cols.items()})
        return self._chain.readings(p, len(theta)) + self.layout.frame

    def predict(self, theta: np.ndarray) -> np.ndarray:
        """Observations ``(n, m)``: each reading minus its nominal, in its covariance frame, mm."""
        theta = np.asarray(theta, dtype=float)
        single = theta.ndim == 1
        r = self.readings(theta) - self.layout.nominal
        out = np.einsum("kji,nkj->nki", self.layout.rotation, r).reshape(len(r), -1)
        return out[0] if single else out

    def centres(self, theta: np.ndarray) -> np.ndarray:
        """The readings ``(k, 3)`` for one ``theta`` (p,), in the reading frame, mm (:func:`reading_centres`)."""
        return reading_centres(self.layout, self.predict(theta))

    __call__ = predict


class LinearProbeModel:
    """First-order probe model: the Jacobian of the ``htm-thesis`` probe model at zero, a design ``(m, p)``."""

    name = "linear"

    def __init__(self, campaign, space: ParameterSpace | None = None, layout: ProbeLayout | None = None):
        from ...models.jacobian import jacobian

        kin = ProbeModel(campaign, "htm-thesis", space, layout)
        self.campaign, self.space, self.layout = campaign, kin.space, kin.layout
        self.observations = kin.observations
        self.design = jacobian(kin)

    def predict(self, theta: np.ndarray) -> np.ndarray:
        return np.asarray(theta, dtype=float) @ self.design.T

    def centres(self, theta: np.ndarray) -> np.ndarray:
        """The first-order readings ``(k, 3)`` for one ``theta`` (p,), in the reading frame, mm."""
        return reading_centres(self.layout, self.predict(theta))

    __call__ = predict


def reading_centres(layout: ProbeLayout, observations: np.ndarray) -> np.ndarray:
    """Readings ``(k, 3)`` in the reading frame, mm, of a model's ``observations`` (m,) = Qᵀ (reading − nominal):
    each turned back to the reading frame's axes and added to its nominal."""
    return layout.nominal + np.einsum("kij,kj->ki", layout.rotation, observations.reshape(-1, 3))
