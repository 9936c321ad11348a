"""Touch-probe runs as candidate measurements, valued through the probe likelihood (SPEC §6, §17).

A probe candidate is a new run of the touch probe: a sphere probed at indexed B angles with one stylus
(a B-axis run) or at indexed C angles on the table (a C-axis run).  Its rows come from the linear probe
model (the machine's ``linear`` probe model, the first order of the kinematic probe model) of a
campaign holding only that run; the run brings its own nuisance terms — the stylus's ``xS, yS, dRS, rS``
and the datum ``xD, yD, zD`` of its readings (a new session is zeroed anew), the sphere's placement ``xP,
yP`` for a C-axis run — whose names carry the candidate's id (``xD[b_axis#P1]``), so they join the
planner's parameter space beside the campaign's own.  Each reading's noise is the probe's repeatability
squared plus ``sigma_model_probe²`` at the rms of its prior.

The catalogue (when the campaign has a ``[probe]`` with a repeatability and a stylus):

* **B = 0°, 45°, 90°** with each stylus: the Y steps at 45° and 90° separate ``alpha_XB`` and
  ``gamma_XB`` (at 90° the probe sees only their sum), the readings a ball-bar reading convention cannot
  change (docs/conventions.md);
* **B = 0°, 90° with a stylus 100 mm longer**: a third lever for ``beta_XB``;
* **C at eight angles** (every 45°), **the sphere 100 mm higher**, **at another radius**: the C tilts
  ``alpha_CZ``, ``beta_CZ`` from more positions or longer levers.
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from ..campaign import BAxisProbe, CAxisProbe, Probe, Stylus
from ..models import build_model
from ..parameters import ParameterSpace

#: repeats of each reading of a probe candidate
PROBE_REPEATS = 2
#: a longer stylus of the catalogue, mm added to the campaign's longest
LONGER_STYLUS_MM = 100.0
#: the sphere raised by this much in the catalogue, mm
HIGHER_SPHERE_MM = 100.0
#: other sphere radii of the catalogue, mm
OTHER_SPHERE_R_C_MM = (50.0, 150.0)


@dataclass(frozen=True)
class ProbeCandidate:
    """One candidate probe run.

    ``run``: ``"b_axis"`` or ``"c_axis"``; ``angles_deg`` the indexed B or C angles; ``stylus_length`` and
    ``ball_radius`` (mm) the stylus (programmed length, to the ball's tip when ``ball_radius`` > 0);
    ``R_C``, ``Z_C`` (mm) the sphere on the table (C-axis run: its radius and height; B-axis run: its height);
    ``repeats`` per reading; ``id`` the suffix of its nuisance terms' owners.
    """

    name: str
    id: str
    run: str
    angles_deg: tuple[float, ...]
    stylus_length: float
    ball_radius: float
    R_C: float
    Z_C: float
    repeats: int = PROBE_REPEATS
    datum: str = "first"
    kind: str = "probe"
    repeat_of: int | None = None
    extension: float | None = None

    @property
    def pattern(self) -> str:
        return "probe B" if self.run == "b_axis" else "probe C"

    @property
    def length(self) -> float:
        """No bar: the candidate's "length" is nan (a ball-bar candidate's bar length)."""
        return float("nan")

    def probe(self, repeatability: float, X_T: float) -> Probe:
        """The candidate's run as a campaign's ``[probe]`` (zero readings: the rows do not depend on them)."""
        a = len(self.angles_deg)
        zeros = np.zeros((self.repeats, a, 3))
        angles = np.array(self.angles_deg, dtype=float)
        p = Probe("candidate", repeatability)
        if self.run == "b_axis":
            st = Stylus(self.id, self.stylus_length, None, zeros, ball_radius=self.ball_radius)
            p.b_axis = BAxisProbe(X_T, angles, {self.id: st}, Z_C=self.Z_C)
        else:
            p.c_axis = CAxisProbe(self.R_C, self.Z_C, np.array([-X_T, 0.0]), angles, zeros, R_B=self.stylus_length,
                                  ball_radius=self.ball_radius, datum=self.datum)
        return p

    def owner(self, owner: str) -> str:
        """The planner's name of one of the run's owners (``b_axis`` → ``b_axis#<id>``; its stylus keeps its id)."""
        return owner if owner == self.id else f"{owner}#{self.id}"

    def terms(self, campaign) -> list[tuple[str, str]]:
        """Its own nuisance terms as ``(owner, base)`` pairs, owners named for the planner."""
        return [(self.owner(o), b) for o, b in self.probe(campaign.probe.repeatability, 0.0).nuisance_terms()]

    def rows(self, campaign, space: ParameterSpace, deviations, table) -> tuple[np.ndarray, np.ndarray]:
        """Its rows ``(k, P)`` over the planner's ``space`` and their base noise ``(k,)`` mm² (the repeatability; the
        planner adds ``sigma_model_probe²``): the machine's first-order probe model of a campaign holding this run
        alone, over ``deviations`` (names of ``table``) and the run's own terms."""
        one = copy.copy(campaign)
        X_T = campaign.probe.b_axis.X_T if campaign.probe.b_axis is not None else campaign.primary_setup().X_T
        one.probe = self.probe(campaign.probe.repeatability, X_T)
        own = one.probe.nuisance_terms()
        sub = ParameterSpace([], [], deviations, own, table=table)
        model = build_model("linear", one, sub, "probe")  # the machine's first-order probe model
        rename = {f"{b}[{o}]": f"{b}[{self.owner(o)}]" for o, b in own}
        A = np.zeros((model.design.shape[0], len(space)))
        A[:, [space.index(rename.get(n, n)) for n in sub.names]] = model.design
        return A, model.observations.noise_variance()


def probe_catalogue(campaign) -> list[ProbeCandidate]:
    """The probe candidates of ``campaign`` (module docstring); none without a usable ``[probe]``."""
    p = campaign.probe
    if p is None or p.repeatability is None or p.b_axis is None or not p.b_axis.styli:
        return []
    styli = list(p.b_axis.styli.values())
    Z_C = p.b_axis.Z_C if p.b_axis.Z_C is not None else (p.c_axis.Z_C if p.c_axis is not None else
                                                          campaign.mount_for("BX").Z_C)
    out = []
    for k, st in enumerate(styli):
        out.append(ProbeCandidate(f"probe B 0/45/90° ({st.id} stylus)", f"P{len(out) + 1}", "b_axis",
                                  (0.0, 45.0, 90.0), st.R_B, st.ball_radius, 0.0, Z_C))
    longest = max(styli, key=lambda s: s.R_B)
    out.append(ProbeCandidate(f"probe B 0/90° (stylus {longest.R_B + LONGER_STYLUS_MM:g} mm)", f"P{len(out) + 1}",
                              "b_axis", (0.0, 90.0), longest.R_B + LONGER_STYLUS_MM, longest.ball_radius, 0.0, Z_C))
    c = p.c_axis
    if c is not None and campaign.probe_gap() is None:  # a C-axis run of a known stylus (probe_skipped says why not)
        st = p.b_axis.styli.get(c.stylus) if c.stylus else None
        length, radius = (st.R_B, st.ball_radius) if st else (c.R_B, c.ball_radius)
        every45 = tuple(float(a) for a in range(0, 360, 45))
        out.append(ProbeCandidate(f"probe C at 8 angles (R_C {c.R_C:g} mm)", f"P{len(out) + 1}", "c_axis", every45,
                                  length, radius, c.R_C, c.Z_C, datum=c.datum))
        out.append(ProbeCandidate(f"probe C 0/90/180/270°, sphere {c.Z_C + HIGHER_SPHERE_MM:g} mm high",
                                  f"P{len(out) + 1}", "c_axis", (0.0, 90.0, 180.0, 270.0), length, radius, c.R_C,
                                  c.Z_C + HIGHER_SPHERE_MM, datum=c.datum))
        for R_C in OTHER_SPHERE_R_C_MM:
            if R_C != c.R_C:
                out.append(ProbeCandidate(f"probe C 0/90/180/270°, R_C {R_C:g} mm", f"P{len(out) + 1}", "c_axis",
                                          (0.0, 90.0, 180.0, 270.0), length, radius, R_C, c.Z_C, datum=c.datum))
    return out


def probe_skipped(campaign) -> list[str]:
    """Sentences naming the probe candidates the catalogue leaves out, and why (empty when none is)."""
    p = campaign.probe
    gap = campaign.probe_gap()
    if gap is None or p is None or p.repeatability is None or p.b_axis is None or not p.b_axis.styli:
        return []
    return [gap.skipped("the touch-probe candidates on the C axis (more angles, another sphere height or radius)")]


def probe_feasibility(candidate: ProbeCandidate, campaign) -> tuple[bool, str]:
    """Whether the sphere positions of a C-axis run fit the X and Y travels (a B-axis run always does)."""
    travel = campaign.machine.travel
    if candidate.run != "c_axis" or not travel:
        return True, "within the axis travels" if travel else "no axis travels in [machine]: not checked"
    over = [f"{a} span {2 * candidate.R_C:.0f} mm > travel {travel[a]:g} mm" for a in "XY"
            if a in travel and 2 * candidate.R_C > travel[a]]
    return (not over), ("; ".join(over) if over else "within the axis travels")
