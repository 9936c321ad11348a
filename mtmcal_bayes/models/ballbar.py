"""The ball-bar model of a campaign (SPEC §19): each run simulated as a ΔL trace and reduced to eccentricities.

One model for every machine; only its *kernel*, the geometry that turns commands into bar lengths, is a choice:

* :class:`ChainKernel`, the engine's: the machine's :class:`~.chain.Chain` (``Chain.ballbar_lengths``), analytic in
  the parameters (complex-step derivatives go through);
* a plug-in's own (the thesis': its Eq 2.10 with explicit pivots, ``plugins/thesis/kinematic.py``).

The model owns what does not depend on the kernel.  Its evaluation points are one table: the placement of each
mount's W ball first (one point per mount, the thesis way: where the actual tool ball, the dummy sphere with the
true tool length and no ball offset, is at the home rotary pose over the mount's W-ball position), then every
run's points, the commands of the engine's patterns (:func:`~mtmcal_bayes.machines.patterns.pattern_commands`) with
the run's arc, held axes and bar side as its campaign states them.  Its parameter columns: the deviations, the
setup terms ``xT, yT, zT, dRB`` and the mount terms ``xW, yW, zW`` per point (absent from the space: zero).  Each
run's trace is read by the least-squares fit that reads measured traces, ``dL = r0 + e_1 cos ψ + e_2 sin ψ``.

A kernel has ``name``, ``complex_step`` (whether ``lengths`` carries complex parameters) and
``lengths(points, dev, setup_terms, w_off)``: the actual bar length ``|T − W|`` ``(n, k)`` mm at every point of a
:class:`BallbarPoints` table, from the deviation values ``dev`` ``{name: (n,)}`` (those of the space; absent: zero),
the setup terms ``{xT, yT, zT, dRB: (n, k)}`` and the W-ball offsets ``w_off`` ``(n, k, 3)``, all mm and rad.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..machines.chain import Chain
from ..machines.deviations import generated
from ..machines.patterns import (
    components,
    fit_basis,
    pattern_commands,
    placement_commands,
)
from ..machines.plugins import provided
from ..machines.space import described_space
from ..observations import Observations
from ..parameters import MOUNT_NUISANCE, SETUP_NUISANCE, nuisance_name
from ..patterns import EccentricityFit

#: rows × points of a parameter batch evaluated at once: the kernels' temporaries are (rows, k, 3) arrays, sooner
#: done where they stay in the processor's cache (a designed campaign's 10 000 points: 16 rows at a time took 0.6×
#: the time of 256, the same numbers to the bit)
CHUNK_POINTS = 1 << 17


def as_numbers(theta) -> np.ndarray:
    """A parameter batch as floats, or as complex numbers where it is (a complex-step derivative)."""
    theta = np.asarray(theta)
    return theta if np.iscomplexobj(theta) else theta.astype(float)


def nuisance_columns(space, names_of_points) -> dict:
    """``{base: (k,) column}`` of each nuisance base over the points (-1: absent, reads zero)."""
    col = {name: i for i, name in enumerate(space.names)}
    return {b: np.array([col.get(nuisance_name(b, o), -1) for o in owners], dtype=int)
            for b, owners in names_of_points.items()}


def extended(theta: np.ndarray, space) -> tuple[np.ndarray, dict]:
    """``(theta (n, p) with a zero column appended, {deviation: (n,)})``: column -1 reads an absent term as zero."""
    ext = np.concatenate([theta, np.zeros((len(theta), 1), dtype=theta.dtype)], axis=1)
    return ext, {p.name: ext[:, i] for i, p in enumerate(space.parameters) if p.group == "deviation"}


def placing_runs(ballbar) -> dict[str, int]:
    """The run that places each mount's W ball (its dummy sphere), by mount: the first run on it.  Every run on a
    mount depends on that run's setup, so the runs of a mount are not simulated without it."""
    first: dict[str, int] = {}
    for i, run in enumerate(ballbar.runs):
        first.setdefault(run.mount, i)
    return first


@dataclass(frozen=True)
class BallbarRun:
    """One block of points: a run (``pattern``, its polar angles ``psi`` (k,) rad) or a mount's W-ball placement
    (``pattern`` None, one point); ``q`` its commands ``{letter: (k,)}`` mm and rad."""

    pattern: str | None
    setup: str
    mount: str
    q: dict
    psi: np.ndarray | None = None


def _basis(desc, run: BallbarRun, comps: tuple[str, str]) -> np.ndarray:
    """The fit's design matrix ``(k, 3)`` of a run: 1, then the term of each component of ``comps`` (the machine's
    order of them): cos ψ for a pattern's first component, sin ψ for its second (:func:`fit_basis`).  In the
    machine's order, the fit is the one its measured traces are read by, to the last bit (the thesis' B patterns:
    1, sin ψ, cos ψ for ex, ez)."""
    D = fit_basis(run.psi)
    first = components(desc, run.pattern)
    return D[:, [0] + [1 + first.index(c) for c in comps]]


@dataclass(frozen=True)
class BallbarPoints:
    """Every evaluation point of a model in one table (k points: the mounts' placements, then the runs).

    ``q`` commands ``{letter: (k,)}``; ``length`` the programmed tool length (k,) mm; ``dummy`` (k,) the placement
    points (the dummy sphere: true tool length, no ball offset); ``placement`` (k,) the index of the point that
    places each point's W ball; ``setup``, ``mount`` (k,) the setup and mount ids; ``runs`` the slice of each run;
    ``setup_cols``, ``mount_cols`` ``{base: (k,)}`` the parameter column of each nuisance term (-1: absent)."""

    q: dict
    length: np.ndarray
    dummy: np.ndarray
    placement: np.ndarray
    setup: np.ndarray
    mount: np.ndarray
    runs: list
    setup_cols: dict
    mount_cols: dict


class ChainKernel:
    """The engine's kernel: the ball bar through the machine's chain.  Tool ball: the spindle's ``point_mm`` plus
    ``(R_B + dRB)`` along the spindle, offset by ``xT, yT, zT`` (frame axes at the home pose; not the dummy
    sphere's); W ball placed on the dummy sphere, offset by ``xW, yW, zW`` in the workpiece frame."""

    name = "chain"
    complex_step = True

    def __init__(self, desc):
        self.chain = Chain(desc, generated(desc))

    def lengths(self, pts: BallbarPoints, dev: dict, setup_terms: dict, w_off: np.ndarray) -> np.ndarray:
        t_off = np.stack([setup_terms[b] for b in ("xT", "yT", "zT")], axis=-1) * (~pts.dummy)[None, :, None]
        return self.chain.ballbar_lengths(pts.length + setup_terms["dRB"], t_off, pts.q, placement=pts.placement,
                                          w_off=w_off, dev=dev)


class BallbarModel:
    """Ball-bar eccentricities of a campaign: ``(n, p)`` -> ``(n, m)`` mm, through ``kernel`` (default: the
    machine's chain, :class:`ChainKernel`).

    ``campaign`` in the engine's terms (its machine's description, its mounts' W-ball positions, its runs' arcs
    and bar sides); ``space`` default: the machine's ball-bar space; ``observations``: the campaign's, if made.
    """

    def __init__(self, campaign, space=None, *, kernel=None, observations: Observations | None = None):
        self.campaign = campaign
        self.desc = desc = campaign.machine.description
        self.kernel = kernel or ChainKernel(desc)
        self.name = self.kernel.name
        self.complex_step = self.kernel.complex_step  # predict carries complex parameters where the kernel does
        self.space = space or described_space(campaign, data="ballbar")
        self.observations = observations or Observations.from_campaign(campaign)
        bb = campaign.ballbar
        self.placements = []
        for mount, i in placing_runs(bb).items():
            setup = bb.runs[i].setup
            q = placement_commands(desc, length=bb.setups[setup].R_B, ball=bb.mounts[mount].centre())
            self.placements.append(BallbarRun(None, setup, mount, q))
        self.runs = []
        for run in bb.runs:
            cmd = bb.run_commands(run, bb) if bb.run_commands is not None else None
            if cmd is None:
                cmd = pattern_commands(desc, run.pattern, length=bb.setups[run.setup].R_B,
                                       ball=bb.mounts[run.mount].centre(), bar=bb.length, arc_deg=bb.arc_of(run),
                                       hold_deg=run.hold_deg, reverse=bb.bar_reversed(run))
            self.runs.append(BallbarRun(run.pattern, run.setup, run.mount, cmd.q, cmd.psi))
        comp_index = {(key.run, key.component): j for j, key in enumerate(self.observations.keys)}
        ordered = provided(campaign.machine, "pattern_components") or (lambda p: components(desc, p))
        self._components = [tuple(ordered(run.pattern)) for run in bb.runs]
        self._out = [[(comp_index.get((i, c)), j) for j, c in enumerate(comps)]
                     for i, comps in enumerate(self._components)]
        self._basis = [_basis(desc, run, comps) for run, comps in zip(self.runs, self._components)]
        self._pinv = [np.linalg.pinv(D) for D in self._basis]
        self._points = None

    def replace_commands(self, run: int, q: dict) -> None:
        """Simulate run ``run`` with other commands ``{letter: (k,)}`` from now on (a compensated program)."""
        old = self.runs[run]
        self.runs[run] = BallbarRun(old.pattern, old.setup, old.mount, q, old.psi)
        self._points = None

    def points(self) -> BallbarPoints:
        """The table of every evaluation point (:class:`BallbarPoints`)."""
        if self._points is None:
            blocks = self.placements + self.runs
            sizes = [len(b.psi) if b.pattern is not None else 1 for b in blocks]
            starts = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
            letters = list(blocks[0].q)
            q = {a: np.concatenate([np.broadcast_to(b.q[a], (k,)) for b, k in zip(blocks, sizes)]) for a in letters}
            setup = np.concatenate([[b.setup] * k for b, k in zip(blocks, sizes)])
            mount = np.concatenate([[b.mount] * k for b, k in zip(blocks, sizes)])
            placed = {b.mount: starts[i] for i, b in enumerate(self.placements)}
            n_place = len(self.placements)
            R_B = {s: v.R_B for s, v in self.campaign.ballbar.setups.items()}
            self._points = BallbarPoints(
                q=q, length=np.array([R_B[s] for s in setup], dtype=float),
                dummy=np.arange(starts[-1]) < starts[n_place],
                placement=np.array([placed[m] for m in mount], dtype=int), setup=setup, mount=mount,
                runs=[slice(starts[n_place + i], starts[n_place + i + 1]) for i in range(len(self.runs))],
                setup_cols=nuisance_columns(self.space, {b: setup for b in SETUP_NUISANCE}),
                mount_cols=nuisance_columns(self.space, {b: mount for b in MOUNT_NUISANCE}))
        return self._points

    def _dL(self, theta: np.ndarray) -> np.ndarray:
        """ΔL ``(n, k)`` mm at every point, for a batch ``(n, p)``."""
        pts = self.points()
        ext, dev = extended(theta, self.space)
        setup_terms = {b: ext[:, c] for b, c in pts.setup_cols.items()}  # (n, k)
        w_off = np.stack([ext[:, pts.mount_cols[b]] for b in MOUNT_NUISANCE], axis=-1)  # (n, k, 3)
        return self.kernel.lengths(pts, dev, setup_terms, w_off) - self.campaign.ballbar.length

    def traces(self, theta: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
        """ΔL traces of every run: ``(psi (k,) rad, dL (n, k) mm)`` each, :data:`CHUNK_POINTS` rows × points at a
        time."""
        theta = np.atleast_2d(as_numbers(theta))
        rows = max(1, CHUNK_POINTS // len(self.points().length))
        dL = np.concatenate([self._dL(theta[i:i + rows]) for i in range(0, len(theta), rows)])
        return [(run.psi, dL[:, sl]) for run, sl in zip(self.runs, self.points().runs)]

    def eccentricities(self, theta: np.ndarray) -> list[EccentricityFit]:
        """Per run, the fit of its simulated trace: ``coef`` (n, 3) r0, e_1, e_2 mm, its components, its rms."""
        out = []
        for (_, dL), D, pinv, comps in zip(self.traces(theta), self._basis, self._pinv, self._components):
            coef = dL @ pinv.T
            out.append(EccentricityFit(coef, comps, np.sqrt(np.mean(np.abs(dL - coef @ D.T) ** 2, axis=-1))))
        return out

    def column_support(self) -> np.ndarray:
        """``(m, p)`` whether observation ``i`` can depend on parameter ``j``: a deviation every one; a set-up's or a
        mount's nuisance term those of the runs whose points carry it, or whose W ball's placement point does (the
        Jacobian's structure: columns of disjoint support share one evaluation, :func:`.jacobian.complex_step_jacobian`)."""
        pts = self.points()
        p = len(self.space)
        point = np.zeros((len(pts.length), p + 1), dtype=bool)  # the last column: absent terms (-1)
        point[:, [i for i, q in enumerate(self.space.parameters) if q.group == "deviation"]] = True
        rows = np.arange(len(pts.length))
        for cols in pts.setup_cols.values():
            point[rows, cols] = True
            point[rows, cols[pts.placement]] = True
        for cols in pts.mount_cols.values():
            point[rows, cols] = True
        out = np.zeros((len(self.observations), p), dtype=bool)
        for sl, cols in zip(pts.runs, self._out):
            run = point[sl, :p].any(axis=0)
            for i, _ in cols:
                if i is not None:
                    out[i] = run
        return out

    def predict(self, theta: np.ndarray) -> np.ndarray:
        """Eccentricities, mm: ``(n, p)`` -> ``(n, m)``; ``(p,)`` -> ``(m,)``."""
        theta = as_numbers(theta)
        single = theta.ndim == 1
        theta2 = np.atleast_2d(theta)
        out = np.empty((len(theta2), len(self.observations)), dtype=theta.dtype)
        for (_, dL), pinv, cols in zip(self.traces(theta2), self._pinv, self._out):
            coef = dL @ pinv.T  # (n, 3): r0, e_1, e_2
            for i, j in cols:
                if i is not None:
                    out[:, i] = coef[:, 1 + j]
        return out[0] if single else out

    __call__ = predict


#: the engine's ball-bar model is the ball-bar model with its default kernel, the chain (the name kept for callers)
ChainBallbarModel = BallbarModel
