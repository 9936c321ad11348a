"""Touch-probe runs as candidate measurements, one catalogue for every machine (SPEC §6, §19): indexed positions of
each rotary axis, the measurement of the controllers' kinematics cycles, valued through the probe likelihood.

The catalogue of :func:`probe_catalogue` (a campaign with a ``[probe]`` giving a repeatability and a stylus), with the
campaign's first stylus and its first run's sphere (a described machine's probe without runs: the R-test's sphere,
else the first W-ball mount's position, else the stylus ball at the home pose):

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
from .candidates import WithoutBar
from ..machines.patterns import tool_home
from .catalogue import hold_for, holds_within, rules_of, travel_problems

#: repeats of each reading of a probe candidate
PROBE_REPEATS = 2
#: a longer stylus of the catalogue, mm added to the campaign's first
LONGER_STYLUS_MM = 100.0
#: the sphere raised by this much (along Z) in the catalogue, mm
HIGHER_SPHERE_MM = 100.0
#: what the plan says of its probe candidates (``{sigma_probe}``: µm)
PROBE_NOTE = ("touch-probe runs (kind 'probe'): each rotary axis indexed to 0° and up to three more positions, alone, "
              "with the others held, with a longer stylus or the sphere higher; each a new run with its own stylus "
              "and sphere terms, readings with the probe's repeatability and sigma_model_probe = {sigma_probe:.2f} µm "
              "(rms of its prior)")


@dataclass(frozen=True)
class ProbeCandidate(WithoutBar):
    """One candidate probe run: ``name``; ``id`` the owner of its sphere terms; ``positions``
    ``((letter, (angles°...)), ...)`` (each axis one angle per position), ``angles_deg`` the indexed axis' angles;
    ``sphere`` (3,) mm at the home pose (``Z_C`` its height, ``R_C`` 0: the plan's table columns); ``stylus`` the
    campaign's stylus it re-sets, of ``stylus_length`` mm to the ball's centre; ``axis`` the indexed axis;
    ``repeats`` per reading."""

    name: str
    id: str
    angles_deg: tuple[float, ...]
    stylus_length: float
    R_C: float
    Z_C: float
    repeats: int = PROBE_REPEATS
    positions: tuple = ()
    sphere: tuple = (0.0, 0.0, 0.0)
    stylus: str = ""
    axis: str = ""
    kind: str = "probe"
    repeat_of: int | None = None
    extension: float | None = None

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

    def renewed(self) -> set[tuple[str, str]]:
        """The ``(group, owner)`` of the terms a further run of it sets anew: its stylus' and its sphere's (all its
        terms: a further run re-qualifies the stylus and re-places the sphere)."""
        return {("probe", self.id), ("probe", f"{self.stylus}#{self.id}")}

    def terms(self, campaign) -> list[tuple[str, str]]:
        """Its own nuisance terms as ``(owner, base)`` pairs."""
        return probe_terms(campaign.machine.description, self.alone(campaign).probe)

    def model(self, campaign, deviations, table):
        """Its kinematic model: the probe model through the chain on a campaign of this run alone, over its own
        space (``deviations`` and its terms); :meth:`rows` are its first order."""
        own = ParameterSpace([], [], deviations, self.terms(campaign), table=table)
        return ChainProbeModel(self.alone(campaign), own)

    def rows(self, campaign, space: ParameterSpace, deviations, table) -> tuple[np.ndarray, np.ndarray]:
        """Its rows ``(3k, P)`` over ``space`` and their base noise ``(3k,)`` mm² (repeatability² / repeats)."""
        model = FirstOrderModel(self.model(campaign, deviations, table))
        A = np.zeros((model.design.shape[0], len(space)))
        A[:, [space.index(n) for n in model.space.names]] = model.design
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
    return (0.0,) + holds_within(ax)[:3]


def probe_catalogue(campaign) -> list[ProbeCandidate]:
    """The probe candidates of a campaign (module docstring); none without a usable ``[probe]``."""
    p = campaign.probe
    if p is None or p.repeatability is None or not p.styli or (not p.runs and campaign.machine.description is None):
        return []
    desc = campaign.machine.description
    rules = rules_of(campaign)
    positions = dict(rules.probe_positions)
    stylus = next(iter(p.styli))
    length = p.centre_length(stylus)
    sphere = np.asarray(p.runs[0].sphere if p.runs else _sphere_without_runs(campaign, length), float)
    out: list[ProbeCandidate] = []

    def add(name, ax, angles, *, held=(), length_mm=length, at=sphere):
        k = len(angles)
        pos = [(ax.letter, tuple(angles))] + [(a, (v,) * k) for a, v in held]
        cid = f"candidate{len(out) + 1}"  # the owner of its sphere terms: no campaign run is named so
        out.append(ProbeCandidate(name, cid, tuple(angles), float(length_mm), 0.0, float(at[2]), PROBE_REPEATS,
                                  positions=tuple(pos), sphere=tuple(float(x) for x in at), stylus=stylus,
                                  axis=ax.letter))

    for ax in desc.rotary_axes:
        angles = positions.get(ax.letter) or _positions(ax)
        shown = "/".join(f"{a:g}" for a in angles)
        add(f"probe {ax.letter} {shown}° ({stylus} stylus)", ax, angles)
        held = hold_for(desc, ax.letter) if rules.hold else None
        if held:
            add(f"probe {ax.letter} {shown}°, " + ", ".join(f"{a} at {v:g}°" for a, v in held), ax, angles,
                held=held)
        add(f"probe {ax.letter} {shown}° (stylus {length + LONGER_STYLUS_MM:g} mm)", ax, angles,
            length_mm=length + LONGER_STYLUS_MM)
        add(f"probe {ax.letter} {shown}°, sphere {HIGHER_SPHERE_MM:g} mm higher", ax, angles,
            at=sphere + np.array([0.0, 0.0, HIGHER_SPHERE_MM]))
    return out


def _sphere_without_runs(campaign, length: float) -> np.ndarray:
    """Where the catalogue puts the sphere of a campaign whose probe has no run yet, mm (home pose): the R-test's
    sphere, else the first W-ball mount's position, else the stylus ball's centre at the home pose (every axis at
    0: the sphere under the stylus)."""
    rt = campaign.rtest
    if rt is not None and rt.sphere is not None:
        return np.asarray(rt.sphere, float)
    mounts = list(campaign.ballbar.mounts.values())
    if mounts and getattr(mounts[0], "position", None) is not None:
        return np.asarray(mounts[0].position, float)
    return tool_home(campaign.machine.description, length)


def probe_feasibility(candidate: ProbeCandidate, campaign) -> tuple[bool, str]:
    """Whether every position's commands lie within the described travels."""
    return travel_problems(campaign.machine.description, candidate.commands(campaign))


__all__ = ["ProbeCandidate", "probe_catalogue", "probe_feasibility", "PROBE_NOTE", "PROBE_REPEATS"]
