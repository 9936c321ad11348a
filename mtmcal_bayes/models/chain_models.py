"""Forward models of a campaign on a described machine (SPEC §19): ``(n, p)`` -> ``(n, m)`` in one call (the
ball bar's: :mod:`.ballbar`).

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
from ..machines.patterns import nominal_down, tool_home
from ..machines.probe_terms import SPHERE_TERMS, stylus_terms
from ..machines.space import described_space
from ..observations import DescribedProbeKey, ProbeObservations
from .ballbar import as_numbers, extended, nuisance_columns
from .chain import Chain
from .jacobian import complex_step_jacobian

#: fixed-point steps of a probe reading's linear axes
SOLVE_STEPS = 4


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
        self._cols = nuisance_columns(self.space, {**{b: styli for b in self._stylus_terms},
                                           **{b: owners for b in SPHERE_TERMS}})
        tool = tool_home(desc, 0.0) + self.length[:, None] * desc.spindle.direction
        w_rot = nominal_down(self.sphere, desc.work_chain, self.q_rot)
        t_rot = nominal_down(tool, desc.tool_chain, self.q_rot)
        self.nominal = np.stack([(w_rot - t_rot)[:, i] for i in range(3)], axis=-1)  # (k, 3) X, Y, Z
        self.observations = described_probe_observations(campaign, self.nominal)

    def readings(self, theta: np.ndarray) -> np.ndarray:
        """Commanded X, Y, Z ``(n, k, 3)`` at which the stylus centre reaches the sphere centre, mm."""
        theta = np.atleast_2d(as_numbers(theta))
        ext, dev = extended(theta, self.space)
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
        theta = as_numbers(theta)
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
        return as_numbers(theta) @ self.design.T

    def centres(self, theta: np.ndarray) -> np.ndarray:
        """A probe model's first-order readings ``(k, 3)`` for one ``theta`` (p,): X, Y, Z, mm."""
        return self.nominal + self.predict(theta).reshape(-1, 3)

    __call__ = predict
