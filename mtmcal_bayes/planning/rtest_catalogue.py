"""R-test runs as candidate measurements (SPEC §22, docs/rtest.md "Planning R-test runs"), one catalogue for every
machine, valued through the R-test's likelihood like the ball bar's and the probe's candidates.

The catalogue of :func:`rtest_catalogue` (a campaign with an ``[rtest]``: a nest, and a sphere by :func:`set_up`),
per rotary axis K of the machine:

* K **indexed** over its travel at :data:`INDEXED_POSITIONS` positions (a full turn from 0 where it turns fully; its
  travel's ends and evenly between otherwise; ±90° where the description states no travel), the other rotary axes
  at 0;
* the same with the other rotary axes **held** at each of the first :data:`HELD_ANGLES` angles of
  :data:`~.catalogue.HOLD_DEG` their travels allow (one candidate per angle);
* K **swept** over the same range alone, the positions logged every :data:`SWEEP_STEP_DEG` on the move (the model
  takes a sweep as its logged positions: the machine's quasi-static errors, not its dynamics).

Every candidate is in the frame and zero of the campaign's first R-test run, else ``"tool"``/``"first"``: the
sensors' own axes, zeroed at the first position, what most devices export raw (docs/rtest.md, "A device's export").
The sphere stays where it is and the nest in the spindle: a candidate shares the campaign's placement and nest terms
(with R-test data they are the posterior's; else their priors), and brings its own zero (``zero = "first"``).  Its
readings' noise is the R-test's repeatability (1 µm where none is stated) squared over the repeats, plus
``sigma_model_rtest²`` (the rms of its prior) added by the planner.  Its machine minutes are the time model's
(:func:`~mtmcal_bayes.machine_time.rtest_run_minutes`), the nest's set-up included where the campaign has no R-test
run yet.  Its angles lie within the travels by construction; it is feasible when the linear commands that keep the
nest on the sphere lie within theirs.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from .. import units
from ..campaign import RTest, RTestNest, RTestRun
from ..machine_time import TimeModel, rtest_run_minutes
from ..machines.patterns import tool_home
from ..machines.probe_terms import rtest_terms
from ..models.chain_models import FirstOrderModel
from ..models.probe import DEFAULT_REPEATABILITY
from ..models.rtest import RTestLayout, RTestModel
from ..parameters import ParameterSpace
from .candidates import WithoutBar
from .catalogue import holds_within, travel_problems

#: positions of an indexed candidate over its axis' travel
INDEXED_POSITIONS = 6
#: held angles of the other rotary axes per indexed axis (the first of HOLD_DEG within their travels)
HELD_ANGLES = 2
#: a sweep's logged positions, every this many degrees
SWEEP_STEP_DEG = 10.0
#: repeats of each position of a candidate
RTEST_REPEATS = 1
#: the nest's length when ``[rtest]`` names none, mm (docs/rtest.md)
DEFAULT_NEST_MM = 150.0
#: where the travel is not stated, an axis is indexed over ±this, degrees
UNSTATED_TRAVEL_DEG = 90.0
#: the frame and zero of candidates on a campaign without an R-test run
DEFAULT_FRAME, DEFAULT_ZERO = "tool", "first"
#: what the plan says of its R-test candidates
RTEST_NOTE = ("R-test runs (kind 'rtest'): each rotary axis indexed over its travel at {n} positions alone and with "
              "the others held, or swept alone (logged every {step:g}°); sphere {sphere} mm, nest {nest} "
              "({length:g} mm), frame {frame!r}, zero {zero!r}; readings with the R-test's repeatability and "
              "sigma_model_rtest = {sigma:.2f} µm (rms of its prior); minutes from the time model ({why})")


@dataclass(frozen=True)
class RTestSetUp:
    """Where the R-test candidates are measured: the sphere ``sphere`` (3,) mm (home pose, workpiece side) of
    placement ``placement``, the nest ``nest`` of ``length`` mm, the frame and zero, and why each was chosen."""

    sphere: tuple
    placement: str
    nest: str
    length: float
    calibrated: bool
    frame: str
    zero: str
    measured: bool  # the campaign has R-test runs (the set-up is in place: its minutes are not counted again)
    why: str


def set_up(campaign) -> RTestSetUp | None:
    """The R-test set-up of ``campaign``'s candidates, None without an ``[rtest]``: the first run's sphere, placement,
    nest, frame and zero; on a campaign without runs, ``[rtest] sphere_mm`` (else the first probe run's sphere, else the
    nest's centre at the home pose: the sphere under the nest with every axis at 0), its first nest and
    "tool"/"first"."""
    rt = campaign.rtest
    if rt is None or campaign.machine.description is None:
        return None
    if rt.runs:
        run = rt.runs[0]
        nest = rt.nests[run.nest]
        return RTestSetUp(tuple(float(x) for x in run.sphere), rt.placement_of(run), run.nest, nest.length,
                          nest.calibrated, run.frame, run.zero, True, f"those of run {run.id!r}")
    nid, nest = next(iter(rt.nests.items()), ("N1", RTestNest(DEFAULT_NEST_MM)))
    probe = campaign.probe.runs if campaign.probe is not None else []
    if rt.sphere is not None:
        sphere, where = rt.sphere, "[rtest] sphere_mm"
    elif probe:
        sphere, where = probe[0].sphere, f"that of probe run {probe[0].id!r}"
    else:
        sphere, where = tool_home(campaign.machine.description, nest.length), "the nest's centre at the home pose"
    return RTestSetUp(tuple(float(x) for x in sphere), "sphere", nid, nest.length, nest.calibrated, DEFAULT_FRAME,
                      DEFAULT_ZERO, False, f"sphere: {where}; frame and zero: the default (no R-test run yet)")


@dataclass(frozen=True)
class RTestCandidate(WithoutBar):
    """One candidate R-test run: ``name``; ``id`` the owner of its zero; ``positions`` ``((letter, (angles°...)),
    ...)`` (each rotary axis one angle per position); ``axis`` the indexed or swept axis; ``sweep_span`` its swept
    span, degrees (None: indexed); ``setup`` its :class:`RTestSetUp`; ``repeats`` per position."""

    name: str
    id: str
    positions: tuple
    axis: str
    setup: RTestSetUp
    sweep_span: float | None = None
    repeats: int = RTEST_REPEATS
    kind: str = "rtest"
    repeat_of: int | None = None
    extension: float | None = None

    @property
    def n_positions(self) -> int:
        return len(self.positions[0][1])

    def angles_deg(self) -> dict[str, list[float]]:
        """``angles_deg`` of its ``[[rtest.runs]]`` table."""
        return {a: [float(v) for v in vals] for a, vals in self.positions}

    def run(self) -> RTestRun:
        """The candidate as an R-test run (zero readings: the rows do not depend on them)."""
        s = self.setup
        return RTestRun(self.id, s.nest, np.asarray(s.sphere, float),
                        {a: units.to_internal(np.asarray(v, float), "deg") for a, v in self.positions},
                        np.zeros((self.repeats, self.n_positions, 3)), s.frame, s.zero, s.placement)

    def alone(self, campaign):
        """A copy of ``campaign`` whose R-test holds this run alone (its nest, its instrument and priors)."""
        one = copy.copy(campaign)
        rt = campaign.rtest
        one.rtest = RTest(rt.instrument, rt.repeatability, rt.placement_sd, rt.nest_length_sd, rt.nest_offset_sd,
                          nests={self.setup.nest: RTestNest(self.setup.length, self.setup.calibrated)},
                          runs=[self.run()])
        return one

    def renewed(self) -> set[tuple[str, str]]:
        """The ``(group, owner)`` of the terms a further run of it sets anew: its zero (the sphere and the nest stay)."""
        return {("rtest", self.id)}

    def terms(self, campaign) -> list[tuple[str, str]]:
        """Its nuisance terms as ``(owner, base)`` pairs: its zero, the placement's and the nest's (shared)."""
        return rtest_terms(campaign.machine.description, self.alone(campaign).rtest)

    def model(self, campaign, deviations, table) -> RTestModel:
        """Its kinematic model: the R-test model through the chain on a campaign of this run alone, over its own
        space (``deviations`` and its terms); :meth:`rows` are its first order."""
        own = ParameterSpace([], [], deviations, table=table, rtest=self.terms(campaign))
        return RTestModel(self.alone(campaign), own)

    def rows(self, campaign, space: ParameterSpace, deviations, table) -> tuple[np.ndarray, np.ndarray]:
        """Its rows ``(3k, P)`` over ``space`` (first order of the R-test model) and their base noise ``(3k,)``
        mm² (the repeatability squared over the repeats)."""
        model = FirstOrderModel(self.model(campaign, deviations, table))
        design = model.design
        A = np.zeros((design.shape[0], len(space)))
        A[:, [space.index(n) for n in model.space.names]] = design
        sd = campaign.rtest.repeatability if campaign.rtest.repeatability is not None else DEFAULT_REPEATABILITY
        return A, np.full(len(A), sd**2 / self.repeats)

    def commands(self, campaign) -> dict:
        """The commanded axes of every position: rotary (rad) and X, Y, Z keeping the nest on the sphere (mm)."""
        layout = RTestLayout(self.alone(campaign))
        return {**layout.angles, **layout.linear}

    def minutes(self, model: TimeModel) -> float:
        """Its machine minutes (:func:`~mtmcal_bayes.machine_time.rtest_run_minutes`), the nest's set-up included
        where the campaign has no R-test run yet."""
        return rtest_run_minutes(model, self.n_positions, self.repeats, sweep_span_deg=self.sweep_span,
                                 set_up=not self.setup.measured)


def axis_range(ax) -> tuple[float, float, bool]:
    """``(start, end, full turn)`` of an axis' range in degrees: a full turn from 0, else its travel (±
    :data:`UNSTATED_TRAVEL_DEG` where none is stated)."""
    if ax.travel is None:
        return -UNSTATED_TRAVEL_DEG, UNSTATED_TRAVEL_DEG, False
    lo, hi = np.rad2deg(ax.travel)
    return (0.0, 360.0, True) if hi - lo >= 360.0 else (float(lo), float(hi), False)


def spread(ax, k: int) -> np.ndarray:
    """``k`` angles over an axis' range (:func:`axis_range`), degrees: a full turn in equal steps from 0 (the last
    short of 360°), else both ends and evenly between."""
    lo, hi, full = axis_range(ax)
    return np.arange(k) * 360.0 / k if full else np.linspace(lo, hi, k) + 0.0  # + 0.0: no -0 printed


def held_angles(ax) -> tuple[float, ...]:
    """The first :data:`HELD_ANGLES` angles of :data:`~.catalogue.HOLD_DEG` within an axis' travel."""
    return holds_within(ax)[:HELD_ANGLES]


def rtest_catalogue(campaign) -> list[RTestCandidate]:
    """The R-test candidates of ``campaign`` (module docstring); none without an ``[rtest]``."""
    s = set_up(campaign)
    if s is None:
        return []
    axes = campaign.machine.description.rotary_axes
    out: list[RTestCandidate] = []

    def add(name, ax, angles, held=(), *, sweep=None):
        k = len(angles)
        pos = [(a.letter, tuple(float(x) for x in angles) if a is ax else (dict(held).get(a.letter, 0.0),) * k)
               for a in axes]
        out.append(RTestCandidate(name, f"rtest candidate {len(out) + 1}", tuple(pos), ax.letter, s, sweep))

    for ax in axes:
        angles = spread(ax, INDEXED_POSITIONS)
        lo, hi, full = axis_range(ax)
        shown = f"{angles[0]:g}…{angles[-1]:g}° ×{len(angles)}"
        add(f"R-test {ax.letter} {shown}", ax, angles)
        others = [a for a in axes if a is not ax]
        for i in range(HELD_ANGLES):
            held = [(a.letter, held_angles(a)[i]) for a in others if len(held_angles(a)) > i]
            if held:
                add(f"R-test {ax.letter} {shown}, " + ", ".join(f"{a} {v:g}°" for a, v in held), ax, angles, held)
        swept = np.arange(lo, hi + 1e-9 - (SWEEP_STEP_DEG if full else 0.0), SWEEP_STEP_DEG) + 0.0
        add(f"R-test {ax.letter} swept {swept[0]:g}…{swept[-1]:g}°", ax, swept,
            sweep=float(swept[-1] - swept[0]))
    return out


def rtest_feasibility(candidate: RTestCandidate, campaign) -> tuple[bool, str]:
    """Whether every position's commands lie within the described travels."""
    return travel_problems(campaign.machine.description, candidate.commands(campaign))


def rtest_note(campaign, candidates: list, sigma_rtest: float) -> str:
    """What the plan says of its R-test candidates (``sigma_rtest`` mm)."""
    s = candidates[0].setup
    return RTEST_NOTE.format(n=INDEXED_POSITIONS, step=SWEEP_STEP_DEG,
                             sphere="[" + ", ".join(f"{x:g}" for x in s.sphere) + "]", nest=s.nest, length=s.length,
                             frame=s.frame, zero=s.zero, sigma=units.from_internal(sigma_rtest, "um"),
                             why=("the nest's set-up not counted: it is in place" if s.measured else
                                  "each with the nest's set-up: the campaign has no R-test run yet") + "; " + s.why)


__all__ = ["RTestCandidate", "RTestSetUp", "rtest_catalogue", "rtest_feasibility", "rtest_note", "set_up",
           "INDEXED_POSITIONS", "SWEEP_STEP_DEG", "RTEST_REPEATS", "DEFAULT_NEST_MM"]
