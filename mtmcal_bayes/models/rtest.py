"""The R-test model of a campaign (SPEC §22): each position's displacement reading, ``(n, p)`` -> ``(n, m)``, m = 3 per
position, mm, through the machine's chain (one model for every machine).

At position j the rotary axes are at the run's angles and the linear axes at the commands that put the nominal
nest centre on the nominal sphere centre through the NOMINAL chain.  The linear axes sit nearer the bed than every
rotary axis (:mod:`mtmcal_bayes.machines.description`), so the nominal chain is a translation by the linear commands
(each along its frame axis, a workpiece-side one the opposite way: ISO 841) of the points the rotary axes turn: the
inverse is ``Σ q_L e_L = w_rot − t_rot`` exactly (the probe's nominal reading, :class:`~.probe.ChainProbeKernel`).

The reading: ``d_j = G_jᵀ (S_j − N_j) − z`` with ``S_j`` the actual sphere centre (the nominal one plus its placement
error ``xPR, yPR, zPR``, carried down the workpiece side), ``N_j`` the actual nest centre (the spindle's ``point_mm``
plus ``(L + dLR)`` along the spindle, offset across it by ``xNR, yNR, zNR``, carried down the tool side), ``G_j``
the sensors' axes: ``"tool"`` the actual rotation of the spindle body (its columns ``T(N + e_i) − T(N)``: the chain is
rigid), ``"machine"`` ``G_jᵀ = F_nom,j F_jᵀ`` (the device turned the readings back with the nominal rotation), and
``z`` the run's zero (``xZR, yZR, zZR``, ``zero = "first"``; else 0).  Analytic in the parameters (complex-step
derivatives go through).

The observation is each position's mean over the repeats; its noise the engine's probe rule (``"pooled"``,
:data:`~.probe.NOISE_RULES`): the repeat scatter pooled over the runs with repeats, else the stated repeatability,
else 1 µm, over the repeats.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from ..machines.chain import Chain
from ..machines.deviations import generated
from ..machines.patterns import centre_commands, nominal_down, tool_home
from ..machines.probe_terms import RTEST_PLACEMENT_TERMS, RTEST_ZERO_TERMS, nest_terms
from ..machines.space import described_space
from ..observations import RTestKey, RTestObservations
from ..parameters import RTEST_NUISANCE
from .ballbar import as_numbers, extended, nuisance_columns
from .probe import NOISE_RULES, _readings


@dataclass(frozen=True)
class _Repeats:
    """A run's readings as the probe's noise rule takes them: ``centres`` (r, a, 3) mm, no fit covariance."""

    centres: np.ndarray
    centre_cov: None = None


class RTestLayout:
    """The positions (k of them) of a campaign's R-test runs, their nominal commands and observations.

    Per position: ``run``, ``placement``, ``nest`` (k,) owners; ``angles`` {letter: (k,)} rad of every rotary axis;
    ``linear`` {X, Y, Z: (k,)} mm the nominal commands; ``sphere`` (k, 3), ``length`` (k,) mm; ``machine`` (k,)
    whether the run reads in the ``"machine"`` frame; ``nominal_rotation`` (k, 3, 3) the spindle body's nominal
    rotation F_nom; ``reading_mean`` (k, 3) mm; ``nominal`` (k, 3) the readings at zero (zeros); ``observations``.  Raises :class:`InputError` for a campaign without
    R-test runs.
    """

    def __init__(self, campaign):
        rt, desc = campaign.rtest, campaign.machine.description
        if rt is None or not rt.runs:
            raise InputError(campaign.source, "rtest", "no R-test readings ([[rtest.runs]])")
        runs = rt.runs
        sizes = [run.positions for run in runs]
        self.slices = [slice(a, b) for a, b in zip(np.cumsum([0] + sizes[:-1]), np.cumsum(sizes))]
        self.run = np.repeat([run.id for run in runs], sizes)
        self.placement = np.repeat([rt.placement_of(run) for run in runs], sizes)
        self.nest = np.repeat([run.nest for run in runs], sizes)
        self.angles = {a.letter: np.concatenate([np.broadcast_to(run.angles.get(a.letter, 0.0), (k,))
                                                 for run, k in zip(runs, sizes)])
                       for a in desc.rotary_axes}
        self.sphere = np.repeat(np.array([run.sphere for run in runs], dtype=float), sizes, axis=0)
        self.length = np.repeat([rt.nests[run.nest].length for run in runs], sizes).astype(float)
        self.machine = np.repeat([run.frame == "machine" for run in runs], sizes)
        self.linear = centre_commands(desc, self.angles, point=self.sphere,
                                      tool=tool_home(desc, 0.0) + self.length[:, None] * desc.spindle.direction)
        k = len(self.run)
        self.nominal_rotation = np.stack([nominal_down(np.broadcast_to(e, (k, 3)), desc.tool_chain, self.angles,
                                                       directions=True) for e in np.eye(3)], axis=-1)
        mean, cov, n, _ = _readings([_Repeats(run.displacements) for run in runs], rt.repeatability, NOISE_RULES[0])
        self.reading_mean = mean
        self.nominal = np.zeros((k, 3))  # the readings with every deviation and term zero: the nest on the sphere
        keys = tuple(RTestKey(run.id, i + 1, c) for run in runs for i in range(run.positions) for c in "XYZ")
        self.observations = RTestObservations(keys, mean.reshape(-1), np.diagonal(cov, axis1=1, axis2=2).reshape(-1),
                                              np.repeat(np.array(n, dtype=int), 3))


class RTestModel:
    """R-test readings of a campaign: ``(n, p)`` -> ``(n, m)``, m = 3 per position, mm (module docstring).

    ``space`` default: the machine's space for R-test data; ``layout``: the campaign's :class:`RTestLayout`, if made.
    """

    name = "chain"
    complex_step = True

    def __init__(self, campaign, space=None, *, layout: RTestLayout | None = None):
        desc = campaign.machine.description
        if desc is None:
            raise InputError(campaign.source, "rtest", "the R-test needs the machine's description")
        self.campaign, self.desc = campaign, desc
        self.chain = Chain(desc, generated(desc))
        self.layout = layout or RTestLayout(campaign)
        self.space = space or described_space(campaign, data="rtest")
        self.observations = self.layout.observations
        L = self.layout
        owners = {**{b: L.run for b in RTEST_ZERO_TERMS}, **{b: L.placement for b in RTEST_PLACEMENT_TERMS},
                  **{b: L.nest for b in RTEST_NUISANCE if b.endswith("NR") or b == "dLR"}}
        self._cols = nuisance_columns(self.space, owners)
        self._offsets = [("xyz".index(b[0]), b) for b in nest_terms(desc)[:-1]]

    def displacements(self, theta: np.ndarray) -> np.ndarray:
        """The readings ``(n, k, 3)`` mm for a batch ``(n, p)``."""
        theta = np.atleast_2d(as_numbers(theta))
        L, s = self.layout, self.desc.spindle
        ext, dev = extended(theta, self.space)
        terms = {b: ext[:, c] for b, c in self._cols.items()}  # (n, k)
        nest = s.point + (L.length + terms["dLR"])[..., None] * s.direction  # (n, k, 3) at the home pose
        offsets = np.zeros(nest.shape, dtype=nest.dtype)
        for i, b in self._offsets:
            offsets[..., i] = terms[b]
        nest = nest + offsets
        k = nest.shape[1]
        # the nest centre and the points one mm along each frame axis from it, carried by the spindle body together
        points = np.concatenate([nest] + [nest + e for e in np.eye(3)], axis=1)  # (n, 4k, 3)
        q4 = {a: np.tile(v, 4) for a, v in {**L.angles, **L.linear}.items()}
        T = self.chain.tool_point(points, q4, dev)
        N = T[:, :k]
        G = np.stack([T[:, (i + 1) * k:(i + 2) * k] - N for i in range(3)], axis=-1)  # (n, k, 3, 3): columns G e_i
        sphere = L.sphere + np.stack([terms[b] for b in RTEST_PLACEMENT_TERMS], axis=-1)
        S = self.chain.work_point(sphere, {**L.angles, **L.linear}, dev)
        d = np.einsum("nkji,nkj->nki", G, S - N)  # Gᵀ (S − N)
        if L.machine.any():
            d = np.where(L.machine[:, None], np.einsum("kij,nkj->nki", L.nominal_rotation, d), d)
        return d - np.stack([terms[b] for b in RTEST_ZERO_TERMS], axis=-1)

    def predict(self, theta: np.ndarray) -> np.ndarray:
        """Observations ``(n, m)`` (``(m,)`` for one ``theta`` (p,)): the readings, mm."""
        theta = as_numbers(theta)
        out = self.displacements(theta).reshape(len(np.atleast_2d(theta)), -1)
        return out[0] if theta.ndim == 1 else out

    __call__ = predict


__all__ = ["RTestModel", "RTestLayout"]
