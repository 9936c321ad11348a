"""Forward models of a campaign on a described machine (SPEC §19): ``(n, p)`` -> ``(n, m)`` in one call.

* :class:`ChainBallbarModel` — each ball-bar run (:mod:`mtmcal_bayes.machines.patterns`) simulated as a ΔL trace
  through the :class:`~.chain.Chain` and reduced to eccentricities by the extractor that reads measured traces;
  the W ball of each mount placed the thesis way, on the actual dummy sphere (true tool length, no ball offset) at
  the home rotary pose.  Tool ball: the spindle's ``point_mm`` plus ``(R_B + dRB)`` along the spindle, offset by
  ``xT, yT, zT`` (frame axes at the home pose; not the dummy sphere's); W ball: offset by ``xW, yW, zW``.
* :class:`ChainProbeModel` — each probed position: the commanded X, Y, Z at which the actual stylus-ball centre
  reaches the actual sphere centre, minus the nominal reading.  The stylus: ``point_mm`` plus ``(L + dRS)`` along
  the spindle and its centring offsets; the sphere at ``sphere_mm`` plus ``xP, yP, zP`` on the workpiece side.
  The linear axes are solved by a fixed-point iteration (their directions are within squareness of the frame
  axes, so each step gains that factor, ~1e-4: :data:`SOLVE_STEPS` steps reach rounding).
* :class:`FirstOrderModel` — the ``linear`` model of a described machine: the chain's Jacobian at the home pose
  (zero deviations), a design matrix.
"""

from __future__ import annotations

import numpy as np

from ..machines.deviations import generated
from ..machines.patterns import (
    components,
    fit_basis,
    nominal_down,
    pattern_commands,
    placement_commands,
    tool_home,
)
from ..machines.probe_terms import SPHERE_TERMS, stylus_terms
from ..machines.space import described_space
from ..observations import DescribedProbeKey, Observations, ProbeObservations
from ..parameters import MOUNT_NUISANCE, SETUP_NUISANCE, nuisance_name
from .chain import Chain
from .jacobian import complex_step_jacobian

#: rows of a parameter batch evaluated at once (memory: a few MB per temporary)
CHUNK = 256
#: fixed-point steps of a probe reading's linear axes
SOLVE_STEPS = 4


def _numbers(theta) -> np.ndarray:
    """A parameter batch as floats, or as complex numbers where it is (a complex-step derivative)."""
    theta = np.asarray(theta)
    return theta if np.iscomplexobj(theta) else theta.astype(float)


def _columns(space, names_of_points) -> dict:
    """``{base: (k,) column}`` of each nuisance base over the points (-1: absent, reads zero)."""
    col = {name: i for i, name in enumerate(space.names)}
    return {b: np.array([col.get(nuisance_name(b, o), -1) for o in owners], dtype=int)
            for b, owners in names_of_points.items()}


def _values(theta: np.ndarray, space, desc) -> tuple[np.ndarray, dict]:
    """``(theta with a zero column appended, {deviation: (n,)})`` of a batch."""
    ext = np.concatenate([theta, np.zeros((len(theta), 1))], axis=1)
    dev = {p.name: ext[:, i] for i, p in enumerate(space.parameters) if p.group == "deviation"}
    return ext, dev


class ChainBallbarModel:
    """Ball-bar eccentricities of a described machine's campaign: ``(n, p)`` -> ``(n, m)``, mm."""

    name = "chain"
    complex_step = True  # predict carries complex parameters: its Jacobian by the complex step

    def __init__(self, campaign, space=None, *, observations: Observations | None = None):
        self.campaign = campaign
        self.desc = campaign.machine.description
        self.space = space or described_space(campaign, data="ballbar")
        self.chain = Chain(self.desc, generated(self.desc))
        self.observations = observations or Observations.from_campaign(campaign)
        bb = campaign.ballbar
        q_parts, lengths, setups, mounts, dummy, self.runs = [], [], [], [], [], []
        first_run: dict[str, int] = {}
        for i, run in enumerate(bb.runs):
            first_run.setdefault(run.mount, i)
        placed: dict[str, int] = {}
        start = 0
        for mount, i in first_run.items():  # the dummy sphere of each mount: one point each, first
            run = bb.runs[i]
            s = bb.setups[run.setup]
            q_parts.append(placement_commands(self.desc, length=s.R_B, ball=bb.mounts[mount].centre()))
            lengths.append([s.R_B]); setups.append([run.setup]); mounts.append([mount]); dummy.append([True])
            placed[mount] = start
            start += 1
        for run in bb.runs:
            s = bb.setups[run.setup]
            cmd = pattern_commands(self.desc, run.pattern, length=s.R_B, ball=bb.mounts[run.mount].centre(),
                                   bar=bb.length, arc_deg=bb.arc_of(run), hold_deg=run.hold_deg,
                                   reverse=bb.bar_reversed(run))
            k = len(cmd.psi)
            q_parts.append(cmd.q)
            lengths.append([s.R_B] * k); setups.append([run.setup] * k); mounts.append([run.mount] * k)
            dummy.append([False] * k)
            self.runs.append((slice(start, start + k), fit_basis(cmd.psi)))
            start += k
        letters = list(q_parts[0])
        self.q = {a: np.concatenate([np.broadcast_to(p[a], (len(np.atleast_1d(p[a])),)) for p in q_parts])
                  for a in letters}
        self.length = np.concatenate([np.asarray(x, float) for x in lengths])
        self.dummy = np.concatenate([np.asarray(x, bool) for x in dummy])
        setup_of = [s for x in setups for s in x]
        mount_of = [m for x in mounts for m in x]
        self.placement = np.array([placed[m] for m in mount_of], dtype=int)
        self._setup_cols = _columns(self.space, {b: setup_of for b in SETUP_NUISANCE})
        self._mount_cols = _columns(self.space, {b: mount_of for b in MOUNT_NUISANCE})
        comp_index = {(key.run, key.component): j for j, key in enumerate(self.observations.keys)}
        self._out = [[(comp_index.get((i, c)), j) for j, c in enumerate(components(self.desc, run.pattern))]
                     for i, run in enumerate(bb.runs)]
        self._pinv = [np.linalg.pinv(D) for _, D in self.runs]

    def _dL(self, theta: np.ndarray) -> np.ndarray:
        """ΔL ``(n, k)`` mm at every point, for a batch ``(n, p)``."""
        ext, dev = _values(theta, self.space, self.desc)
        nui = {b: ext[:, c] for b, c in self._setup_cols.items()}  # (n, k)
        t_off = np.stack([nui["xT"], nui["yT"], nui["zT"]], axis=-1) * (~self.dummy)[None, :, None]
        w_off = np.stack([ext[:, self._mount_cols[b]] for b in MOUNT_NUISANCE], axis=-1)
        return (self.chain.ballbar_lengths(self.length + nui["dRB"], t_off, self.q, placement=self.placement,
                                            w_off=w_off, dev=dev)
                - self.campaign.ballbar.length)

    def traces(self, theta: np.ndarray) -> list[np.ndarray]:
        """ΔL of every run, each ``(n, k_run)`` mm (complex ``theta``: a complex-step derivative goes through)."""
        theta = np.atleast_2d(_numbers(theta))
        dL = np.concatenate([self._dL(theta[i:i + CHUNK]) for i in range(0, len(theta), CHUNK)])
        return [dL[:, sl] for sl, _ in self.runs]

    def predict(self, theta: np.ndarray) -> np.ndarray:
        """Eccentricities, mm: ``(n, p)`` -> ``(n, m)``; ``(p,)`` -> ``(m,)``."""
        theta = _numbers(theta)
        single = theta.ndim == 1
        theta2 = np.atleast_2d(theta)
        out = np.empty((len(theta2), len(self.observations)), dtype=theta.dtype)
        for dL, pinv, cols in zip(self.traces(theta2), self._pinv, self._out):
            coef = dL @ pinv.T  # (n, 3): r0, e_1, e_2
            for i, j in cols:
                if i is not None:
                    out[:, i] = coef[:, 1 + j]
        return out[0] if single else out

    __call__ = predict


class ChainProbeModel:
    """Touch-probe readings of a described machine's campaign: ``(n, p)`` -> ``(n, m)``, m = 3 per position, mm."""

    name = "chain"
    complex_step = True

    def __init__(self, campaign, space=None):
        self.campaign = campaign
        self.desc = desc = campaign.machine.description
        self.space = space or described_space(campaign, data="probe")
        self.chain = Chain(desc, generated(desc))
        probe = campaign.probe
        q_rot, lengths, styli, spheres, owners, self.slices = [], [], [], [], [], []
        start = 0
        for run in probe.runs:
            k = run.positions
            q_rot.append({a.letter: run.angles.get(a.letter, np.zeros(k)) for a in desc.rotary_axes})
            lengths += [probe.styli[run.stylus]] * k
            styli += [run.stylus] * k
            owners += [run.id] * k
            spheres.append(np.broadcast_to(run.sphere, (k, 3)))
            self.slices.append(slice(start, start + k))
            start += k
        self.q_rot = {a.letter: np.concatenate([q[a.letter] for q in q_rot]) for a in desc.rotary_axes}
        self.length = np.asarray(lengths, dtype=float)
        self.sphere = np.concatenate(spheres)
        self._stylus_terms = stylus_terms(desc)
        self._cols = _columns(self.space, {**{b: styli for b in self._stylus_terms},
                                           **{b: owners for b in SPHERE_TERMS}})
        tool = tool_home(desc, 0.0) + self.length[:, None] * desc.spindle.direction
        w_rot = nominal_down(self.sphere, desc.work_chain, self.q_rot)
        t_rot = nominal_down(tool, desc.tool_chain, self.q_rot)
        self.nominal = np.stack([(w_rot - t_rot)[:, i] for i in range(3)], axis=-1)  # (k, 3) X, Y, Z
        self.observations = described_probe_observations(campaign, self.nominal)

    def readings(self, theta: np.ndarray) -> np.ndarray:
        """Commanded X, Y, Z ``(n, k, 3)`` at which the stylus centre reaches the sphere centre, mm."""
        theta = np.atleast_2d(_numbers(theta))
        ext, dev = _values(theta, self.space, self.desc)
        get = {b: ext[:, c] for b, c in self._cols.items()}  # (n, k)
        s = self.desc.spindle
        n = len(theta)
        t = s.point + (self.length + get["dRS"])[..., None] * s.direction
        offsets = np.zeros(t.shape, dtype=t.dtype)
        for b in self._stylus_terms[:-1]:
            offsets[..., "xyz".index(b[0])] = get[b]
        t = t + offsets
        w = self.sphere + np.stack([get[b] for b in SPHERE_TERMS], axis=-1)
        xyz = np.broadcast_to(self.nominal, (n,) + self.nominal.shape).copy()
        for _ in range(SOLVE_STEPS):
            q = dict(self.q_rot, X=xyz[..., 0], Y=xyz[..., 1], Z=xyz[..., 2])
            xyz = xyz + (self.chain.work_point(w, q, dev) - self.chain.tool_point(t, q, dev))
        return xyz

    def predict(self, theta: np.ndarray) -> np.ndarray:
        """Observations ``(n, m)``: each reading minus its nominal, mm."""
        theta = _numbers(theta)
        single = theta.ndim == 1
        out = (self.readings(theta) - self.nominal).reshape(len(np.atleast_2d(theta)), -1)
        return out[0] if single else out

    def centres(self, theta: np.ndarray) -> np.ndarray:
        """The readings ``(k, 3)`` for one ``theta`` (p,): X, Y, Z, mm (the nominal plus :meth:`predict`)."""
        return self.nominal + self.predict(theta).reshape(-1, 3)

    __call__ = predict


def described_probe_observations(campaign, nominal: np.ndarray) -> ProbeObservations:
    """The probe readings of a described campaign minus their ``nominal`` (k, 3), with their noise variance: the
    pooled repeat sd of the repeated positions (else the probe's stated repeatability, else 1 µm) squared over
    the number of repeats."""
    probe = campaign.probe
    keys, means, counts, scatter = [], [], [], []
    for run, sl in zip(probe.runs, _slices(probe)):
        c = run.centres  # (r, a, 3)
        means.append((c.mean(axis=0) - nominal[sl]).reshape(-1))
        counts += [len(c)] * c.shape[1] * 3
        if len(c) > 1:
            scatter.append((len(c) - 1, c.var(axis=0, ddof=1).reshape(-1)))
        for i in range(run.positions):
            for comp in "XYZ":
                keys.append(DescribedProbeKey(run.id, run.stylus, float(i + 1), comp))
    if scatter:
        sd2 = sum(d * v.sum() for d, v in scatter) / sum(d * len(v) for d, v in scatter)
    else:
        sd2 = (probe.repeatability if probe.repeatability is not None else 1e-3) ** 2
    n = np.asarray(counts, dtype=int)
    return ProbeObservations(tuple(keys), np.concatenate(means), np.full(len(n), sd2) / n, n)


def _slices(probe) -> list[slice]:
    out, start = [], 0
    for run in probe.runs:
        out.append(slice(start, start + run.positions))
        start += run.positions
    return out


class FirstOrderModel:
    """The ``linear`` model of a described machine: ``θ ↦ J θ`` with ``J`` the chain's Jacobian at zero."""

    name = "linear"
    complex_step = True

    def __init__(self, chain_model):
        self.campaign, self.space = chain_model.campaign, chain_model.space
        self.observations = chain_model.observations
        self.nominal = getattr(chain_model, "nominal", None)  # a probe model's nominal readings (k, 3), mm
        self.design = complex_step_jacobian(chain_model)

    def predict(self, theta: np.ndarray) -> np.ndarray:
        return _numbers(theta) @ self.design.T

    def centres(self, theta: np.ndarray) -> np.ndarray:
        """A probe model's first-order readings ``(k, 3)`` for one ``theta`` (p,): X, Y, Z, mm."""
        return self.nominal + self.predict(theta).reshape(-1, 3)

    __call__ = predict
