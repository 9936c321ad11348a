"""The thesis' touch-probe sections as the engine's probe runs (thesis Tables 5.1/5.2), translated once, when the
campaign is read or built.

``[probe.c_axis]`` (a sphere on the table at radius R_C and height Z_C, probed at indexed C angles with B = 0) is one
run, id ``c_axis``; ``[probe.b_axis]`` (a sphere on the C-axis centreline probed at indexed B angles with each of its
styli) one run per stylus, id ``b_axis`` (its styli share the sphere, so its datum).  Each run carries what makes it
the thesis':

* its reading frame: the C-axis run's X, Y at the nominal C-axis centreline ``axis_xy`` (``datum = "machine"``) or
  zeroed on the sphere (``"first"``); the B-axis run's anywhere (its sphere's position is its datum ``xD, yD, zD``);
  the Z datum is never stated (``zD`` always a nuisance);
* its terms: per stylus ``xS, yS, dRS, rS`` (``rS`` the effective-radius error, which the thesis' kernel subtracts
  from the length error); the C-axis sphere's placement ``xP, yP``; the datum terms above;
* its observations' keys, which name a position by its indexed angle (:class:`ThesisProbeKey`).

The styli are the B-axis run's (programmed length R_B, to the ball's tip where ``ball_radius_mm`` is given), then the
C-axis run's own where it gives its length (``R_B_mm``, owner ``c_axis``).  A C-axis run that names no stylus
(campaigns written before the key existed) keeps its readings and owner ``c_axis`` without a length: the campaign's
gap (:meth:`~mtmcal_bayes.campaign.Probe.gaps`), which the likelihood refuses by name.

What the thesis' own procedures need beyond the runs (Eqs 5.1–5.19: R_C, ``axis_xy``, X_T, the styli's nominal
readings; the keys as written, to write the campaign back) is the plug-in's record, :class:`ThesisProbe`
(``Probe.own``); the readings stay in the runs (:func:`run_of`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...campaign import Gap, Probe, ProbeRun
from ...observations import ProbeKey

#: the run ids (the owners of their sphere and datum terms, and of the C-axis run's own stylus)
C_RUN, B_RUN = "c_axis", "b_axis"
#: the nuisance terms of a stylus of the thesis' format
STYLUS_TERMS = ("xS", "yS", "dRS", "rS")
#: the datum terms of a reading frame zeroed on the sphere
DATUM = ("xD", "yD", "zD")


@dataclass(frozen=True)
class ThesisProbeKey(ProbeKey):
    """A reading of the thesis' probe runs: ``angle_deg`` the indexed angle (C of the C-axis run, B of the B-axis
    run), degrees."""

    @property
    def group(self) -> str:
        """The reading group: the C-axis run, or the B-axis run of one stylus."""
        return "probe C axis" if self.run == C_RUN else f"probe B axis, stylus {self.stylus}"

    @property
    def label(self) -> str:
        axis = "C" if self.run == C_RUN else "B"
        return f"{self.component}@{axis}{self.angle_deg:g}/{self.stylus}"


@dataclass
class CAxisKeys:
    """``[probe.c_axis]`` as written, without its readings (they are the run ``c_axis``'s): the sphere at ``R_C``,
    ``Z_C`` (mm), the nominal C-axis centreline ``axis_xy`` (2,) mm, the angles (a,) degrees, the stylus it names
    (or its own length ``R_B`` mm and ``ball_radius`` mm) and its ``datum`` (``"machine"`` or ``"first"``)."""

    R_C: float
    Z_C: float
    axis_xy: np.ndarray
    angles_deg: np.ndarray
    stylus: str | None = None
    R_B: float | None = None
    ball_radius: float = 0.0
    datum: str = "machine"


@dataclass
class StylusKeys:
    """A stylus of ``[probe.b_axis.styli]`` as written, without its readings (the run ``b_axis`` of this stylus):
    programmed length ``R_B`` and ``ball_radius`` (mm), and ``nominal`` (b, 3) mm, the nominal centre readings only
    the thesis' Eqs 5.8–5.19 need (None where not given)."""

    id: str
    R_B: float
    nominal: np.ndarray | None = None
    ball_radius: float = 0.0


@dataclass
class BAxisKeys:
    """``[probe.b_axis]`` as written, without its readings: ``X_T`` mm, the B angles (b,) degrees, its styli, the
    sphere's height ``Z_C`` mm where given (else the C-axis sphere's, else the B patterns' mount's)."""

    X_T: float
    angles_deg: np.ndarray
    styli: dict[str, StylusKeys] = field(default_factory=dict)
    Z_C: float | None = None


@dataclass
class ThesisProbe:
    """The thesis plug-in's record of a campaign's probe sections (``Probe.own``)."""

    c_axis: CAxisKeys | None = None
    b_axis: BAxisKeys | None = None


@dataclass
class Readings:
    """One run's readings as given: ``centres`` (r, a, 3) mm, ``centre_cov`` (r, a, 3, 3) mm² where fitted through
    the DPRNT files ``dprnt``."""

    centres: np.ndarray
    centre_cov: np.ndarray | None = None
    dprnt: list[str] | None = None


def thesis_probe(instrument: str, repeatability: float | None, *, c_axis: CAxisKeys | None = None,
                 b_axis: BAxisKeys | None = None, readings: dict, mount_Z: float = np.nan) -> Probe:
    """A probe of the thesis' format in the engine's terms (module docstring): its runs, styli, gap and record.

    ``readings`` {``"c_axis"`` or a B-axis stylus id: :class:`Readings`}; ``mount_Z`` the height, mm, of the B
    patterns' mount, the B-axis sphere's where neither section gives one."""
    probe = Probe(instrument, repeatability)
    add_thesis_runs(probe, c_axis=c_axis, b_axis=b_axis, readings=readings, mount_Z=mount_Z)
    return probe


def add_thesis_runs(probe: Probe, *, c_axis: CAxisKeys | None = None, b_axis: BAxisKeys | None = None,
                    readings: dict, mount_Z: float = np.nan) -> None:
    """The runs, styli, gap and record of the thesis' sections added to ``probe`` (before any ``[[probe.runs]]``:
    the C-axis run, then the B-axis run of each stylus; arguments as :func:`thesis_probe`'s)."""
    probe.own = ThesisProbe(c_axis, b_axis)
    b = b_axis
    for s in (b.styli.values() if b is not None else ()):
        probe.styli[s.id], probe.ball_radii[s.id] = s.R_B, s.ball_radius
    c = c_axis
    if c is not None:
        stylus = c.stylus or C_RUN
        if c.stylus is None and c.R_B is not None:
            probe.styli[C_RUN], probe.ball_radii[C_RUN] = c.R_B, c.ball_radius
        origin = np.array([*c.axis_xy, np.nan]) if c.datum == "machine" else np.full(3, np.nan)
        probe.runs.append(_run(C_RUN, stylus, {"C": c.angles_deg}, sphere=np.array([c.R_C, 0.0, c.Z_C]),
                               given=readings[C_RUN], origin=origin, sphere_terms=("xP", "yP"),
                               datum_terms=("zD",) if c.datum == "machine" else DATUM))
        probe.missing = _gaps(c, b)
    if b is not None:
        Z = b.Z_C if b.Z_C is not None else (c.Z_C if c is not None else mount_Z)
        probe.runs += [_run(B_RUN, s.id, {"B": b.angles_deg}, sphere=np.array([0.0, 0.0, Z]), given=readings[s.id],
                            origin=np.full(3, np.nan), sphere_terms=(), datum_terms=DATUM) for s in b.styli.values()]


def _run(rid: str, stylus: str, angles_deg: dict, *, sphere: np.ndarray, given: Readings, **frame) -> ProbeRun:
    (letter, deg), = angles_deg.items()
    return ProbeRun(rid, stylus, sphere, {letter: np.radians(deg)}, given.centres, given.dprnt, given.centre_cov,
                    stylus_terms=STYLUS_TERMS, key=ThesisProbeKey, labels=deg, section=rid, **frame)


def _gaps(c: CAxisKeys, b: BAxisKeys | None) -> list[Gap]:
    """The C-axis run's stylus where it names none (the deterministic Eqs 5.1–5.7 do not need it)."""
    if c.stylus is not None or c.R_B is not None:
        return []
    styli = sorted(b.styli.values(), key=lambda s: s.R_B) if b is not None else []
    if styli:
        fix = (f"add stylus = \"{styli[0].id}\" (the shortest of [probe.b_axis.styli]: "
               f"{', '.join(s.id for s in styli)}; the one to assume unless you know which probed the C axis) "
               "or give its length R_B_mm")
    else:
        fix = "give its length R_B_mm (and ball_radius_mm when it is measured to the stylus-ball tip)"
    return [Gap("probe.c_axis.stylus", "the C-axis run names no stylus",
                "the touch-probe likelihood (probe or both data) and the comparison of the instruments", fix)]


def record(probe: Probe | None) -> ThesisProbe:
    """The thesis' record of ``probe`` (an empty one where it has none)."""
    own = probe.own if probe is not None else None
    return own if isinstance(own, ThesisProbe) else ThesisProbe()


def run_of(probe: Probe, rid: str, stylus: str | None = None) -> ProbeRun:
    """The run ``rid`` of ``probe`` (with ``stylus``, for the B-axis run of one stylus): its readings."""
    return next(r for r in probe.runs if r.id == rid and (stylus is None or r.stylus == stylus))


def b_mount_height(ballbar) -> float:
    """The height, mm, of the mount the campaign's B patterns use (:meth:`~mtmcal_bayes.campaign.Ballbar.mount_for`;
    NaN without mounts): where the B-axis sphere is where the probe sections give no height."""
    return ballbar.mount_for("BX").Z_C if ballbar.mounts else np.nan
