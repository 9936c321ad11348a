"""The touch-probe model of a campaign (SPEC §12, §19): each probed position's reading, ``(n, p)`` -> ``(n, m)``,
m = 3 per position, mm.

A reading is the commanded X, Y, Z at which the actual stylus-ball centre reaches the actual sphere centre.  One
model for every machine; only its *kernel*, the geometry that turns a position into a reading in the model frame, is
a choice:

* :class:`ChainProbeKernel`, the engine's: the machine's :class:`~.chain.Chain`, the linear axes solved by a
  fixed-point iteration (their directions are within squareness of the frame axes, so each step gains that factor,
  ~1e-4: :data:`SOLVE_STEPS` steps reach rounding); analytic in the parameters (complex-step derivatives go through);
* a plug-in's own (the thesis': the exact affine inverse through its Eq 2.10 with its lever arms,
  ``plugins/thesis/probe_model.py``).

The model owns what does not depend on the kernel, in one :class:`ProbeLayout`: the table of probed positions (run,
stylus, rotary angles, sphere, lengths), the readings with their noise (a rule the machine may state:
:data:`NOISE_RULES`), the covariance frame of a centre fitted through DPRNT points (such a reading is observed along
the principal axes of its fit covariance, so the likelihood stays diagonal), the reading frame (a run whose readings
were zeroed somewhere unknown is placed at its first reading, its datum ``xD, yD, zD`` a broad nuisance), the
nominal readings and the observations.  Its nuisance columns: per stylus ``xS, yS, zS, dRS, rS`` (those the space
has), per run its sphere's ``xP, yP, zP`` and its datum ``xD, yD, zD`` (absent from the space: zero).

A kernel has ``name``, ``complex_step``, ``zero(layout)`` (the readings ``(k, 3)`` mm in the model frame with every
deviation and nuisance term zero) and ``readings(layout, dev, terms, n)``: the readings ``(n, k, 3)`` mm in the model
frame without the datum, from the deviation values ``dev`` ``{name: (n,)}`` and the nuisance terms ``terms``
``{base: (n, k)}`` (mm, rad).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import InputError
from ..machines.chain import Chain
from ..machines.deviations import generated
from ..machines.patterns import nominal_down, tool_home
from ..machines.plugins import provided
from ..machines.probe_terms import stylus_terms
from ..machines.space import described_space
from ..observations import ProbeKey, ProbeObservations
from ..parameters import PROBE_NUISANCE, STYLUS_NUISANCE
from .ballbar import as_numbers, extended, nuisance_columns

#: fixed-point steps of a probe reading's linear axes
SOLVE_STEPS = 4
#: the datum of a run's readings: where its sphere is in the reading frame
DATUM_TERMS = ("xD", "yD", "zD")
#: the probe's reading noise, by rule (a machine's plug-in may state its own, ``probe_noise``):
#: ``"pooled"``: the repeat scatter pooled over every repeated run (else, or where every repeat is equal, the stated
#: repeatability, else 1 µm) over the repeats; ``"run scatter plus repeatability"``: per run its pooled repeat scatter over the repeats (the
#: repeatability where not repeated) plus the stated repeatability, which is then required.  A fitted centre: its
#: fit covariance plus the repeatability².
NOISE_RULES = ("pooled", "run scatter plus repeatability")
#: the repeatability assumed where a campaign states none (rule ``"pooled"``), mm
DEFAULT_REPEATABILITY = 1e-3


def noise_rule(machine) -> str:
    """The rule of ``machine``'s probe noise (:data:`NOISE_RULES`): its plug-in's, else ``"pooled"``."""
    return provided(machine, "probe_noise", NOISE_RULES[0])


def repeatability_required(machine) -> bool:
    """Whether ``machine``'s probe noise takes only a stated repeatability (a probe stating none is then neither
    analysed nor simulated)."""
    return noise_rule(machine) == NOISE_RULES[1]


@dataclass(frozen=True)
class LayoutRun:
    """One probe run in the layout's terms.

    ``id`` owns its sphere and datum terms, ``stylus`` its stylus terms; ``angles`` {axis letter: (a,)} rad (axes
    not named at 0); ``sphere`` (3,) the sphere's nominal centre at the home pose, workpiece side, mm; ``length`` the
    stylus' programmed length, mm (to the ball's tip where ``ball_radius`` > 0, else to its centre); ``centres``
    (r, a, 3) the readings, mm; ``centre_cov`` (r, a, 3, 3) mm² where they were fitted (one repeat), else None;
    ``origin`` (3,) mm the model frame's origin in the reading frame, NaN where unknown (the frame is then placed at
    the first reading and the datum term carries the rest); ``key``, ``labels`` (a,) the observations' key type and
    the label of each position (default its number from 1)."""

    id: str
    stylus: str
    angles: dict
    sphere: np.ndarray
    length: float
    centres: np.ndarray
    centre_cov: np.ndarray | None = None
    ball_radius: float = 0.0
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))
    key: type = ProbeKey
    labels: np.ndarray | None = None

    @property
    def positions(self) -> int:
        return self.centres.shape[1]


def layout_runs(campaign) -> list[LayoutRun]:
    """The campaign's probe runs in the layout's terms: each with its stylus' programmed length and ball radius, its
    reading frame's origin (default the machine frame), its observations' key type and position labels."""
    probe = campaign.probe
    return [LayoutRun(run.id, run.stylus, run.angles, np.asarray(run.sphere, dtype=float),
                      probe.styli.get(run.stylus, np.nan), run.centres, run.centre_cov,
                      probe.ball_radii.get(run.stylus, 0.0),
                      np.zeros(3) if run.origin is None else np.asarray(run.origin, dtype=float),
                      run.key or ProbeKey, run.labels)
            for run in probe.runs]


class ProbeLayout:
    """The probed positions of a campaign's runs (k of them), their readings, frames and observations.

    ``runs`` the :class:`LayoutRun` list (default: the campaign's probe runs, :func:`layout_runs`); ``kernel`` gives
    the nominal readings (default the chain's); ``noise`` one of :data:`NOISE_RULES` (default the machine's).  Per
    position: ``run``, ``stylus`` (k,) owners; ``angles`` {letter: (k,)} rad of every rotary axis of the machine;
    ``sphere`` (k, 3), ``length``, ``ball_radius`` (k,) mm; ``reading_mean`` (k, 3) mm; ``fitted`` (k,);
    ``rotation`` (k, 3, 3) (observation = Qᵀ (reading − nominal)); ``zero`` (k, 3) the nominal readings in the model
    frame, ``frame`` (k, 3) the reading frame's offset from it, ``nominal`` (k, 3) the nominal readings;
    ``observations``.  Raises :class:`InputError` (naming the campaign and key) for probe data the likelihood cannot
    use.
    """

    def __init__(self, campaign, runs: list[LayoutRun] | None = None, kernel=None, *, noise: str | None = None):
        machine, src, probe = campaign.machine, campaign.source, campaign.probe
        if runs is None:
            runs = layout_runs(campaign) if probe is not None else []
        noise = noise or noise_rule(machine)
        if not runs:
            raise InputError(src, "probe", f"no touch-probe readings "
                             f"({provided(machine, 'probe_sections', '[[probe.runs]]')})")
        if noise == NOISE_RULES[1] and probe.repeatability is None:
            raise InputError(src, "probe.repeatability_um", "missing: the probe's repeatability is its noise")
        if (gap := campaign.probe_gap()) is not None:
            raise gap.error(src)
        self.campaign, self.runs = campaign, runs
        sizes = [r.positions for r in runs]
        starts = np.concatenate([[0], np.cumsum(sizes)]).astype(int)
        self.slices = [slice(a, b) for a, b in zip(starts[:-1], starts[1:])]
        self.run = np.concatenate([[r.id] * k for r, k in zip(runs, sizes)])
        self.stylus = np.concatenate([[r.stylus] * k for r, k in zip(runs, sizes)])
        self.angles = {a.letter: np.concatenate([np.broadcast_to(r.angles.get(a.letter, np.zeros(k)), (k,))
                                                 for r, k in zip(runs, sizes)])
                       for a in machine.description.rotary_axes}
        self.sphere = np.concatenate([np.broadcast_to(r.sphere, (k, 3)) for r, k in zip(runs, sizes)])
        self.length = np.array([r.length for r, k in zip(runs, sizes) for _ in range(k)], dtype=float)
        self.ball_radius = np.array([r.ball_radius for r, k in zip(runs, sizes) for _ in range(k)], dtype=float)
        mean, cov, n, fitted = _readings(runs, probe.repeatability, noise)
        self.reading_mean = mean
        self.fitted = fitted
        Q = np.broadcast_to(np.eye(3), cov.shape).copy()
        lam = np.diagonal(cov, axis1=1, axis2=2).copy()
        if fitted.any():
            lam[fitted], Q[fitted] = np.linalg.eigh(cov[fitted])
        self.rotation = Q
        self.zero = (kernel or ChainProbeKernel(machine.description)).zero(self)
        self.frame = self._frame()
        self.has_frame = bool(self.frame.any())
        self.nominal = self.zero + self.frame if self.has_frame else self.zero
        y = mean - self.nominal
        if fitted.any():
            y = np.einsum("kji,kj->ki", Q, y)
        keys = [r.key(r.id, r.stylus, float(lab), f"u{j + 1}" if fitted[sl.start + i] else "XYZ"[j])
                for r, sl in zip(runs, self.slices)
                for i, lab in enumerate(r.labels if r.labels is not None else np.arange(1, r.positions + 1))
                for j in range(3)]
        self.observations = ProbeObservations(tuple(keys), y.reshape(-1), lam.reshape(-1),
                                              np.repeat(np.array(n, dtype=int), 3))

    def _frame(self) -> np.ndarray:
        """Offset ``(k, 3)`` mm from the model frame to the reading frame: a run's ``origin`` where known, else where
        its id's first reading puts it (its datum term, broad, is then centred at zero: the readings' absolute
        value carries no information there).  Runs of one id (one sphere read with several styli) share their datum."""
        frame = np.zeros((len(self.run), 3))
        first: dict[str, int] = {}
        for r, sl in zip(self.runs, self.slices):
            i = first.setdefault(r.id, sl.start)
            known = ~np.isnan(r.origin)
            frame[sl] = self.reading_mean[i] - self.zero[i]
            frame[sl, known] = r.origin[known]
        return frame

    def centres(self, observations: np.ndarray) -> np.ndarray:
        """Readings ``(k, 3)`` in the reading frame, mm, of a model's ``observations`` (m,) = Qᵀ (reading − nominal):
        each turned back to the reading frame's axes and added to its nominal."""
        o = observations.reshape(-1, 3)
        return self.nominal + (np.einsum("kij,kj->ki", self.rotation, o) if self.fitted.any() else o)


def _readings(runs: list[LayoutRun], repeatability: float | None, noise: str):
    """Per position the mean reading (k, 3) mm, its covariance (k, 3, 3) mm², the repeats (k,) and whether it was
    fitted (k,), under the rule ``noise`` (:data:`NOISE_RULES`)."""
    mean, cov, n, fitted, scatter = [], [], [], [], []
    for run in runs:
        c = run.centres
        r, a = c.shape[:2]
        mean.append(c.mean(axis=0))
        n += [r] * a
        fitted += [run.centre_cov is not None] * a
        if run.centre_cov is None and r > 1:
            scatter.append((r - 1, np.var(c, axis=0, ddof=1).reshape(-1)))
    u2 = (repeatability if repeatability is not None else DEFAULT_REPEATABILITY) ** 2
    if noise == NOISE_RULES[0] and scatter:
        pooled = sum(d * v.sum() for d, v in scatter) / sum(d * len(v) for d, v in scatter)
        # every repeat equal (an export rounded coarser than the scatter): the scatter is below the rounding, not
        # zero; the stated repeatability (else 1 µm) is its floor, where a zero would leave the readings no noise
        pooled = pooled if pooled > 0 else u2
    for run in runs:
        c = run.centres
        r, a = c.shape[:2]
        if run.centre_cov is not None:  # one fitted centre per position: its fit covariance plus the repeatability
            cov.append(run.centre_cov[0] + u2 * np.eye(3))
        elif noise == NOISE_RULES[0]:
            cov.append(np.broadcast_to(((pooled if scatter else u2) / r) * np.eye(3), (a, 3, 3)))
        else:  # the pooled scatter of the run's repeats (the repeatability when not repeated), plus it
            s2 = np.sum(np.var(c, axis=0, ddof=1)) / (a * 3) if r > 1 else u2
            cov.append(np.broadcast_to((s2 / r + u2) * np.eye(3), (a, 3, 3)))
    return np.concatenate(mean), np.concatenate(cov), n, np.array(fitted)


class ChainProbeKernel:
    """The engine's kernel: the probe through the machine's chain.  Stylus: the spindle's ``point_mm`` plus
    ``(L + dRS)`` along the spindle (L the length to the stylus-ball centre), offset across it by its centring terms; the sphere at its nominal centre plus
    ``xP, yP, zP`` on the workpiece side."""

    name = "chain"
    complex_step = True

    def __init__(self, desc):
        self.desc = desc
        self.chain = Chain(desc, generated(desc))
        self.terms = stylus_terms(desc)

    def zero(self, layout: ProbeLayout) -> np.ndarray:
        desc = self.desc
        tool = tool_home(desc, 0.0) + (layout.length - layout.ball_radius)[:, None] * desc.spindle.direction
        w_rot = nominal_down(layout.sphere, desc.work_chain, layout.angles)
        t_rot = nominal_down(tool, desc.tool_chain, layout.angles)
        return np.stack([(w_rot - t_rot)[:, i] for i in range(3)], axis=-1)  # (k, 3) X, Y, Z

    def readings(self, layout: ProbeLayout, dev: dict, terms: dict, n: int) -> np.ndarray:
        s = self.desc.spindle
        t = s.point + (layout.length - layout.ball_radius + terms["dRS"])[..., None] * s.direction
        offsets = np.zeros(t.shape, dtype=t.dtype)
        for b in self.terms[:-1]:
            offsets[..., "xyz".index(b[0])] = terms[b]
        t = t + offsets
        w = layout.sphere + np.stack([terms[b] for b in ("xP", "yP", "zP")], axis=-1)
        xyz = np.broadcast_to(layout.zero, (n,) + layout.zero.shape).copy()
        for _ in range(SOLVE_STEPS):
            q = dict(layout.angles, X=xyz[..., 0], Y=xyz[..., 1], Z=xyz[..., 2])
            xyz = xyz + (self.chain.work_point(w, q, dev) - self.chain.tool_point(t, q, dev))
        return xyz


def probe_layout(campaign) -> ProbeLayout:
    """The campaign's probe layout: its plug-in's (the thesis' campaign format), else the engine's."""
    return provided(campaign.machine, "probe_layout", ProbeLayout)(campaign)


class ProbeModel:
    """Touch-probe readings of a campaign: ``(n, p)`` -> ``(n, m)``, m = 3 per position, mm, through ``kernel``
    (default: the machine's chain, :class:`ChainProbeKernel`).

    ``space`` default: the machine's probe space; ``layout``: the campaign's :class:`ProbeLayout`, if made.
    """

    def __init__(self, campaign, space=None, *, kernel=None, layout: ProbeLayout | None = None):
        self.campaign = campaign
        self.kernel = kernel or ChainProbeKernel(campaign.machine.description)
        self.name = self.kernel.name
        self.complex_step = self.kernel.complex_step
        self.layout = layout or ProbeLayout(campaign, kernel=self.kernel)
        self.space = space or described_space(campaign, data="probe")
        self.observations = self.layout.observations
        L = self.layout
        self._cols = nuisance_columns(self.space, {b: (L.stylus if b in STYLUS_NUISANCE else L.run)
                                                   for b in PROBE_NUISANCE})
        self._datum = any((self._cols[b] >= 0).any() for b in DATUM_TERMS)

    @property
    def nominal(self) -> np.ndarray:
        """The nominal readings ``(k, 3)``, mm."""
        return self.layout.nominal

    def readings(self, theta: np.ndarray) -> np.ndarray:
        """Readings ``(n, k, 3)`` in the reading frame, mm, for a batch ``(n, p)``."""
        theta = np.atleast_2d(as_numbers(theta))
        ext, dev = extended(theta, self.space)
        terms = {b: ext[:, c] for b, c in self._cols.items()}  # (n, k)
        r = self.kernel.readings(self.layout, dev, terms, len(theta))
        if self._datum:
            r = r + np.stack([terms[b] for b in DATUM_TERMS], axis=-1)
        return r + self.layout.frame if self.layout.has_frame else r

    def predict(self, theta: np.ndarray) -> np.ndarray:
        """Observations ``(n, m)``: each reading minus its nominal, in its covariance frame, mm."""
        theta = as_numbers(theta)
        single = theta.ndim == 1
        r = self.readings(theta) - self.layout.nominal
        if self.layout.fitted.any():
            r = np.einsum("kji,nkj->nki", self.layout.rotation, r)
        out = r.reshape(len(r), -1)
        return out[0] if single else out

    def centres(self, theta: np.ndarray) -> np.ndarray:
        """The readings ``(k, 3)`` for one ``theta`` (p,), in the reading frame, mm."""
        return self.layout.centres(self.predict(theta))

    __call__ = predict


__all__ = ["ProbeModel", "ProbeLayout", "LayoutRun", "ChainProbeKernel", "layout_runs", "probe_layout",
           "NOISE_RULES", "SOLVE_STEPS", "noise_rule", "repeatability_required"]
