"""Touch-probe runs as candidates on a described machine (SPEC §19): indexed positions of each rotary axis, the
measurement of the controllers' kinematics cycles, valued through the probe likelihood.

The catalogue of :func:`described_probe_catalogue` (a campaign with a ``[probe]`` giving a repeatability and a
stylus), with the campaign's first stylus and its first run's sphere:

* each rotary axis K indexed to 0° and up to three of 90°, −90°, 45°, −45°, 30°, −30° (those its travel
  allows; a fully turning axis to 0/90/180/270°), the other rotary axes at 0;
* the same with the other rotary axes held where the ball-bar catalogue holds them (:func:`.catalogue.hold_for`);
* K's positions with a stylus :data:`LONGER_STYLUS_MM` longer, and with the sphere :data:`HIGHER_SPHERE_MM` higher.

Each candidate is a new run with its own nuisance terms — its stylus' centring and length (a stylus set anew,
owner ``<stylus>#<id>``) and its sphere's placement (owner ``<id>``) — and its readings' noise the probe's
repeatability squared over the repeats, plus ``sigma_model_probe²`` added by the planner.  Its rows are the first
order of :class:`~mtmcal_bayes.models.chain_models.ChainProbeModel` on a campaign of that run alone.  It is feasible
when the commanded X, Y, Z of every position lie within the linear travels.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from .. import units
from ..campaign import Probe, ProbeRun
from ..machines.probe_terms import probe_terms
from ..models.chain_models import ChainProbeModel, FirstOrderModel
from ..parameters import ParameterSpace
from .catalogue import HOLD_DEG, hold_for, travel_problems
from .probe_candidates import PROBE_REPEATS, ProbeCandidate

#: a longer stylus of the catalogue, mm added to the campaign's first
LONGER_STYLUS_MM = 100.0
#: the sphere raised by this much (along Z) in the catalogue, mm
HIGHER_SPHERE_MM = 100.0


@dataclass(frozen=True)
class DescribedProbeCandidate(ProbeCandidate):
    """A touch-probe run of a described machine: ``positions`` ``((letter, (angles°...)), ...)`` (each axis one
    angle per position), ``sphere`` (3,) mm at the home pose, ``stylus`` the campaign's stylus it re-sets, of
    ``stylus_length`` mm; ``axis`` the indexed axis, for the table."""

    positions: tuple = ()
    sphere: tuple = (0.0, 0.0, 0.0)
    stylus: str = ""
    axis: str = ""

    @property
    def pattern(self) -> str:
        return f"probe {self.axis}"

    def probe_run(self) -> ProbeRun:
        """The candidate as a probe run (zero readings: the rows do not depend on them)."""
        k = len(self.positions[0][1])
        return ProbeRun(self.id, f"{self.stylus}#{self.id}", np.asarray(self.sphere, float),
                        {a: units.to_internal(np.asarray(v, float), "deg") for a, v in self.positions},
                        np.zeros((self.repeats, k, 3)))

    def alone(self, campaign):
        """A copy of ``campaign`` whose probe holds this run alone."""
        one = copy.copy(campaign)
        run = self.probe_run()
        one.probe = Probe(campaign.probe.instrument, campaign.probe.repeatability, runs=[run],
                          styli={run.stylus: self.stylus_length})
        return one

    def terms(self, campaign) -> list[tuple[str, str]]:
        """Its own nuisance terms as ``(owner, base)`` pairs."""
        return probe_terms(campaign.machine.description, self.alone(campaign).probe)

    def rows(self, campaign, space: ParameterSpace, deviations, table) -> tuple[np.ndarray, np.ndarray]:
        """Its rows ``(3k, P)`` over ``space`` and their base noise ``(3k,)`` mm² (repeatability² / repeats)."""
        one = self.alone(campaign)
        own = ParameterSpace([], [], deviations, self.terms(campaign), table=table)
        model = FirstOrderModel(ChainProbeModel(one, own))
        A = np.zeros((model.design.shape[0], len(space)))
        A[:, [space.index(n) for n in own.names]] = model.design
        return A, np.full(len(A), campaign.probe.repeatability**2 / self.repeats)

    def commands(self, campaign) -> dict:
        """The commanded axes of every position: rotary (rad) and X, Y, Z reaching the sphere (mm), nominally."""
        m = ChainProbeModel(self.alone(campaign), ParameterSpace([], [], [], self.terms(campaign),
                                                                 table={}))
        q = dict(m.layout.angles)
        q.update({a: m.nominal[:, i] for i, a in enumerate("XYZ")})
        return q


def _positions(ax) -> tuple[float, ...]:
    """0° and up to three more positions of ``ax`` within its travel."""
    if ax.travel is None or np.rad2deg(ax.travel[1] - ax.travel[0]) >= 360.0:
        return (0.0, 90.0, 180.0, 270.0)
    lo, hi = np.rad2deg(ax.travel)
    return (0.0,) + tuple(h for h in HOLD_DEG if lo - 1e-9 <= h <= hi + 1e-9)[:3]


def described_probe_catalogue(campaign) -> list[DescribedProbeCandidate]:
    """The probe candidates of a described campaign (module docstring); none without a usable ``[probe]``."""
    p = campaign.probe
    if p is None or p.repeatability is None or not p.styli or not p.runs:
        return []
    desc = campaign.machine.description
    stylus, length = next(iter(p.styli.items()))
    sphere = np.asarray(p.runs[0].sphere, float)
    out: list[DescribedProbeCandidate] = []

    def add(name, ax, angles, *, held=(), length_mm=length, at=sphere):
        k = len(angles)
        pos = [(ax.letter, tuple(angles))] + [(a, (v,) * k) for a, v in held]
        cid = f"candidate{len(out) + 1}"  # the owner of its sphere terms: no campaign run is named so
        out.append(DescribedProbeCandidate(name, cid, "described", tuple(angles), float(length_mm), 0.0, 0.0,
                                           float(at[2]), PROBE_REPEATS, positions=tuple(pos),
                                           sphere=tuple(float(x) for x in at), stylus=stylus, axis=ax.letter))

    for ax in desc.rotary_axes:
        angles = _positions(ax)
        shown = "/".join(f"{a:g}" for a in angles)
        add(f"probe {ax.letter} {shown}° ({stylus} stylus)", ax, angles)
        held = hold_for(desc, ax.letter)
        if held:
            add(f"probe {ax.letter} {shown}°, " + ", ".join(f"{a} at {v:g}°" for a, v in held), ax, angles,
                held=held)
        add(f"probe {ax.letter} {shown}° (stylus {length + LONGER_STYLUS_MM:g} mm)", ax, angles,
            length_mm=length + LONGER_STYLUS_MM)
        add(f"probe {ax.letter} {shown}°, sphere {HIGHER_SPHERE_MM:g} mm higher", ax, angles,
            at=sphere + np.array([0.0, 0.0, HIGHER_SPHERE_MM]))
    return out


def described_probe_feasibility(candidate: DescribedProbeCandidate, campaign) -> tuple[bool, str]:
    """Whether every position's commands lie within the described travels."""
    return travel_problems(campaign.machine.description, candidate.commands(campaign))


__all__ = ["DescribedProbeCandidate", "described_probe_catalogue", "described_probe_feasibility"]
