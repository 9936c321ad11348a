"""The thesis' touch-probe kernel of the engine's one probe model (:class:`~mtmcal_bayes.models.probe.ProbeModel`)
(SPEC §12): parameter batches ``(n, p)`` -> ``(n, m)``; its campaign's probe runs are read as the engine's
(:mod:`.probe_runs`).

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

The engine's model owns the rest (:mod:`mtmcal_bayes.models.probe`): the table of positions, the datum terms, the
readings with their noise (the thesis' rule: each run's repeat scatter plus the stated repeatability), each fitted
centre's covariance frame, the reading frame and the observations: readings minus their nominal (all deviations and
nuisance terms zero), so every model predicts zero at zero and the ``linear`` model is a design matrix: the
Jacobian of the ``htm-thesis`` probe model at zero, like the ball-bar rows the thesis gives no relation for.
"""

from __future__ import annotations

import numpy as np

from ...models.chain_models import FirstOrderModel
from ...models.probe import ChainProbeKernel, ProbeLayout
from ...models.probe import ProbeModel as EngineProbeModel
from ...parameters import DEVIATIONS, ParameterSpace
from .htm import PIVOTS, CAxis, Geometry, Pivots, t_ball
from .pattern_tables import Commands
from .probe_runs import C_RUN, record

#: the thesis' rule of the probe's noise (:data:`mtmcal_bayes.models.probe.NOISE_RULES`)
NOISE = "run scatter plus repeatability"


def thesis_layout(campaign) -> ProbeLayout:
    """The engine's probe layout of a thesis-format campaign, its nominal readings through ``htm-thesis``."""
    return ProbeLayout(campaign, kernel=thesis_kernel(campaign, PIVOTS["htm-thesis"]), noise=NOISE)


def thesis_kernel(campaign, pivots: Pivots | str = "htm-thesis"):
    """The probe kernel of a thesis campaign: :class:`PivotsProbeKernel` for the runs of its own sections, the
    engine's chain for its ``[[probe.runs]]`` (:class:`RunsOfTwoKernels` where it has both)."""
    runs = campaign.probe.runs if campaign.probe is not None else []
    theirs = {r.id for r in runs if r.section is None}
    if not theirs:
        return PivotsProbeKernel(campaign, pivots)
    chain = ChainProbeKernel(campaign.machine.description)
    if len(theirs) == len({r.id for r in runs}):
        return chain
    return RunsOfTwoKernels(PivotsProbeKernel(campaign, pivots), chain, theirs)


class RunsOfTwoKernels:
    """A probe kernel that reads the positions of the runs ``other_runs`` (ids) through ``other`` and the rest
    through ``own``: each kernel sees its positions as a layout of their own (:class:`_Part`)."""

    complex_step = False

    def __init__(self, own, other, other_runs):
        self.own, self.other, self.other_runs = own, other, tuple(other_runs)
        self.name = own.name
        self._parts = None

    def parts(self, L: ProbeLayout):
        """``(mask (k,) of the other kernel's positions, own part, other part)`` of layout ``L``."""
        if self._parts is None or self._parts[0] is not L:
            mask = np.isin(L.run, self.other_runs)
            self._parts = (L, mask, _Part(L, ~mask), _Part(L, mask))
        return self._parts[1:]

    def zero(self, L: ProbeLayout) -> np.ndarray:
        mask, own, other = self.parts(L)
        out = np.empty((len(mask), 3))
        out[~mask], out[mask] = self.own.zero(own), self.other.zero(other)
        return out

    def readings(self, L: ProbeLayout, dev: dict, terms: dict, n: int) -> np.ndarray:
        mask, own, other = self.parts(L)
        own.zero, other.zero = L.zero[~mask], L.zero[mask]
        out = np.empty((n, len(mask), 3))
        for part, at, kernel in ((own, ~mask, self.own), (other, mask, self.other)):
            out[:, at] = kernel.readings(part, dev, {b: v[..., at] for b, v in terms.items()}, n)
        return out


class _Part:
    """The positions ``at`` (k,) bool of a probe layout, as a layout of their own for one kernel."""

    def __init__(self, L: ProbeLayout, at: np.ndarray):
        self.run, self.stylus = L.run[at], L.stylus[at]
        self.angles = {a: v[at] for a, v in L.angles.items()}
        self.sphere, self.length, self.ball_radius = L.sphere[at], L.length[at], L.ball_radius[at]
        self.zero = None


class PivotsProbeKernel:
    """The thesis' probe kernel: the stylus a tool of :func:`~.htm.t_ball` (lever arms ``R_B`` its centre length,
    ``Z_T`` the head's dimension less it, ``X_T``), the C-axis run's sphere carried by :class:`~.htm.CAxis`, the
    B-axis run's fixed in the model frame; the commands from the exact affine inverse."""

    complex_step = False

    def __init__(self, campaign, pivots: Pivots | str = "htm-thesis"):
        self.pivots = PIVOTS[pivots] if isinstance(pivots, str) else pivots
        self.name = self.pivots.name
        primary = campaign.primary_setup()
        self.head = primary.R_B + primary.Z_T
        b = record(campaign.probe).b_axis
        self.X_T = b.X_T if b is not None else primary.X_T
        self._arms = None

    def geometry(self, L: ProbeLayout) -> Geometry:
        """The lever arms of every position (k,), mm: R_B the stylus' centre length, Z_T the head less it, X_T, the
        sphere's height Z_C and radius R_C."""
        if self._arms is None or self._arms[0] is not L:
            R_B = L.length - L.ball_radius
            k = len(R_B)
            self._arms = (L, Geometry(R_B, self.head - R_B, np.full(k, float(self.X_T)), L.sphere[:, 2].copy(),
                                      L.sphere[:, 0].copy()))
        return self._arms[1]

    def zero(self, L: ProbeLayout) -> np.ndarray:
        return self.readings(L, {}, {}, 1)[0]

    def readings(self, L: ProbeLayout, dev: dict, terms: dict, n: int) -> np.ndarray:
        """Readings ``(n, k, 3)`` in the model frame, without the datum, mm (absent terms zero)."""
        k = len(L.run)
        zeros = np.zeros((n, k))
        get = lambda name, shape: terms.get(name, np.zeros(shape))  # noqa: E731
        dev = {d: dev.get(d, np.zeros(n)) for d in DEVIATIONS}
        g = self.geometry(L)
        B, C = L.angles["B"], L.angles["C"]
        is_c = L.run == C_RUN
        # the actual sphere centre, model frame (n, k, 3)
        S = np.zeros((n, k, 3))
        S[..., 2] = g.Z_C
        if is_c.any():
            x0 = g.R_C + get("xP", (n, k))
            y0 = get("yP", (n, k))
            cC, sC = np.cos(C), np.sin(C)
            turned = np.stack([cC * x0 - sC * y0, sC * x0 + cC * y0, np.broadcast_to(g.Z_C, (n, k))], axis=-1)
            S_c = CAxis(dev, g.Z_C, self.pivots).to_machine(turned)
            S = np.where(is_c[None, :, None], S_c, S)
        # the stylus tool point at the nominal command and at unit steps of X, Y, Z (affine in the command)
        tool = {**dev, "xT": get("xS", (n, k)), "yT": get("yS", (n, k)), "zT": zeros,
                "dRB": get("dRS", (n, k)) - get("rS", (n, k))}
        nominal_S = np.zeros((k, 3))
        nominal_S[:, 2] = g.Z_C
        nominal_S[is_c, 0] = g.R_C[is_c] * np.cos(C[is_c])
        nominal_S[is_c, 1] = g.R_C[is_c] * np.sin(C[is_c])
        down = np.stack([-np.sin(B), np.zeros(k), -np.cos(B)], axis=-1)  # R(B)·(0, 0, −1)
        cmd0 = nominal_S - down * g.R_B[:, None]
        steps = np.concatenate([cmd0, cmd0 + [1.0, 0, 0], cmd0 + [0, 1.0, 0], cmd0 + [0, 0, 1.0]])
        tile = lambda a: np.tile(a, 4)  # noqa: E731
        cmd = Commands(steps[:, 0], steps[:, 1], steps[:, 2], tile(B), tile(C), np.zeros(4 * k))
        geo4 = Geometry(*(tile(v) for v in (g.R_B, g.Z_T, g.X_T, g.Z_C, g.R_C)))
        p4 = {name: (np.tile(v, (1, 4)) if np.ndim(v) == 2 else v) for name, v in tool.items()}
        T = t_ball(p4, geo4, cmd, self.pivots).reshape(n, 4, k, 3)
        M = np.stack([T[:, 1] - T[:, 0], T[:, 2] - T[:, 0], T[:, 3] - T[:, 0]], axis=-1)  # (n, k, 3, 3)
        command = cmd0 + np.linalg.solve(M, (S - T[:, 0])[..., None])[..., 0]
        return command + down * L.length[:, None]


def ProbeModel(campaign, pivots: Pivots | str = "htm-thesis", space: ParameterSpace | None = None,
               layout: ProbeLayout | None = None) -> EngineProbeModel:
    """Touch-probe readings of a thesis-format campaign under ``pivots`` (``"htm-literal"``, ``"htm-thesis"`` or a
    :class:`~.htm.Pivots`): the engine's probe model with :class:`PivotsProbeKernel`; ``space`` default: the
    deviations and the probe's nuisance terms."""
    return EngineProbeModel(campaign, space or ParameterSpace.for_campaign(campaign, data="probe"),
                            kernel=thesis_kernel(campaign, pivots), layout=layout or thesis_layout(campaign))


def LinearProbeModel(campaign, space: ParameterSpace | None = None,
                     layout: ProbeLayout | None = None) -> FirstOrderModel:
    """First-order probe model: the Jacobian of the ``htm-thesis`` probe model at zero, a design ``(m, p)``."""
    return FirstOrderModel(ProbeModel(campaign, "htm-thesis", space, layout))
