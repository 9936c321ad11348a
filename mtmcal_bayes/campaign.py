"""A calibration campaign as plain dataclasses: machine, ball-bar setups, mounts and runs, probe data.

Values are in internal units (mm, rad).  Files are read and written by
:mod:`mtmcal_bayes.io` (``load_campaign``, ``save_campaign``, format
``mtmcal-campaign/1``, see ``docs/campaign-format.md``); a campaign built in
Python is used the same way.
"""

from __future__ import annotations

import dataclasses
import datetime
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import units
from .errors import InputError
from .machines import MachineDescription
from .machines.plugins import provided
from .machines.probe_terms import SPHERE_TERMS, probe_terms, rtest_terms
from .pattern_frames import chain_frame
from .patterns import B_PATTERNS, C_PATTERNS


#: the reference temperature of geometric results (ISO 1:2022), °C
REFERENCE_TEMPERATURE_C = 20.0

@dataclass
class Machine:
    name: str = ""
    configuration: str = ""
    travel: dict[str, float] = field(default_factory=dict)  # axis letter -> travel, mm
    serial: str = ""  # the machine's identifier: campaigns with one serial form its history
    type: str = ""  # the machine's type (make and model): machines of one type share a σ_model hyper-distribution
    description: MachineDescription | None = None  # its kinematic description (SPEC §19); None: the thesis machine


@dataclass
class Setup:
    """Tool setup of the T-side ball: lever arms in mm (thesis Table 4.3)."""

    id: str
    R_B: float
    Z_T: float
    X_T: float


@dataclass
class Mount:
    """Placement of the W-side ball: height above the table and radius, mm."""

    id: str
    Z_C: float
    R_C: float
    position: np.ndarray | None = None  # the W-ball centre (3,) at the home pose, mm (None: from R_C and Z_C)

    def centre(self) -> np.ndarray:
        """The W-ball centre (3,) at the home pose, mm: ``position``, or where the thesis' keys place it, at radius
        R_C along X from the C axis at height Z_C above the table (a B pattern's mount has R_C = 0, Table 2.2)."""
        return np.asarray(self.position, float) if self.position is not None else np.array([self.R_C, 0.0, self.Z_C])


@dataclass
class Run:
    """One ball-bar run: pattern, setup, mount and the repeats of each component (mm) as its reading convention
    reports them (:mod:`mtmcal_bayes.conventions`: :func:`~mtmcal_bayes.conventions.machine_repeats` gives them in
    the machine frame the models predict in)."""

    pattern: str
    setup: str
    mount: str
    repeats: dict[str, np.ndarray] = field(default_factory=dict)  # "ex" -> (r,) mm, as reported (its convention)
    trace_csv: list[str] | None = None  # trace files as written in the campaign, one repeat each
    trace_rms: list[dict[str, float]] | None = None  # fit rms per file and direction, mm
    convention: str | None = None  # how its offsets were read (conventions.py); None: the campaign's
    alternative_convention: str | None = None  # the best reading rejected for it, where its reading was a choice
    arc_deg: np.ndarray | None = None  # a described machine's: the swivelled axis' angles, degrees (None: default)
    hold_deg: dict[str, float] | None = None  # a described machine's: the other rotary axes' positions, degrees
    reversed: bool = False  # the T ball on the other side of the W ball (machines/patterns) from where its pattern puts it

    def mean(self, component: str) -> float:
        """Mean of the repeats of ``component``, mm."""
        return float(np.mean(self.repeats[component]))

    @property
    def label(self) -> str:
        return f"{self.pattern}@{self.setup}/{self.mount}"


@dataclass
class PlannedRun:
    """A ball-bar run planned but not yet measured (``planned = true`` in the file, docs/campaign-format.md):
    where and how often to measure, without data.  ``repeats`` is the number of repeats planned; ``minutes``
    the machine time expected for it, ``why`` the planner's reason, ``order`` its place in the measuring order
    (as given in the file), ``length`` the bar length, mm, when it differs from the campaign's (else None)."""

    pattern: str
    setup: str
    mount: str
    repeats: int
    convention: str | None = None  # how its offsets will be read (conventions.py); None: the campaign's
    minutes: float | None = None
    why: str = ""
    order: int | None = None
    length: float | None = None  # bar length, mm, when not the campaign's [ballbar] length_mm
    arc_deg: np.ndarray | None = None  # a described machine's: the swivelled axis' angles, degrees (None: default)
    hold_deg: dict[str, float] | None = None  # a described machine's: the other rotary axes' positions, degrees
    reversed: bool = False  # the T ball on the other side of the W ball (machines/patterns) from where its pattern puts it

    @property
    def label(self) -> str:
        return f"{self.pattern}@{self.setup}/{self.mount}"

    def describe(self) -> str:
        """``BX@RB1/B, 3 repeats`` with the bar length, the planned minutes and the reason where given."""
        text = f"{self.label}, {self.repeats} repeat{'s' if self.repeats != 1 else ''}"
        if self.length is not None:
            text += f", bar {self.length:g} mm"
        if self.minutes is not None:
            text += f", ~{self.minutes:g} min"
        return text + (f" ({self.why})" if self.why else "")


@dataclass
class Ballbar:
    length: float  # L_B, mm
    accuracy: float  # instrument accuracy, mm
    instrument: str = ""
    feed_mm_per_min: float | None = None
    setups: dict[str, Setup] = field(default_factory=dict)
    mounts: dict[str, Mount] = field(default_factory=dict)
    runs: list[Run] = field(default_factory=list)
    cr_geometry: str = "RC-LB"  # T ball of CR at radius R_C − L_B (Table 2.3) or R_C + L_B (Fig 2.6)
    convention: str = "thesis"  # how the runs' offsets were read (conventions.py), unless a run says otherwise
    planned: list[PlannedRun] = field(default_factory=list)  # runs without data yet, in measuring order
    alternative_reason: str = ""  # one line: why the runs' conventions were preferred to their alternative_convention
    # the frames its runs are read against (conventions.run_frame), from its machine's chain: set when the campaign
    # is read, and by Campaign.__post_init__ when it is built in Python
    pattern_frames: Callable | None = None
    # the patterns whose bar the campaign's format puts on the other side of the W ball from the engine's patterns
    # (machines/patterns): the thesis' BT, and its CR in the geometry of Fig 2.6 (its campaign keys)
    reversed_patterns: frozenset[str] = frozenset()
    # the arc (k,) degrees of a run of a pattern that gives none, where the campaign's format fixes it (the thesis'
    # grids: B 0–90° by 1°, C 0–355° by 5°); elsewhere the swivelled axis' default (machines/patterns)
    pattern_arcs: dict[str, np.ndarray] = field(default_factory=dict)
    # a run's commands and polar angles, ``(run, ballbar) -> PatternCommands or None``, where the campaign's format
    # fixes them (the thesis': Tables 2.2/2.3 as printed); None: the engine's patterns' (machines/patterns)
    run_commands: Callable | None = None

    def bar_reversed(self, run) -> bool:
        """Whether ``run``'s T ball is on the other side of the W ball from where the engine's pattern puts it: the
        run's own ``reversed``, turned over where its campaign's format names the pattern reversed."""
        return run.reversed != (run.pattern in self.reversed_patterns)

    def arc_of(self, run) -> np.ndarray | None:
        """The swivelled axis' angles of ``run`` (k,) degrees: its own, else its campaign format's for its pattern;
        None: the axis' default grid."""
        return run.arc_deg if run.arc_deg is not None else self.pattern_arcs.get(run.pattern)

    def mount_for(self, pattern: str) -> Mount:
        """The mount the runs use for patterns of the same axis (B or C) as ``pattern``, else a sensible one: the
        first with R_C = 0 for B patterns, with R_C > 0 for C patterns (an ``IndexError`` without mounts)."""
        family = B_PATTERNS if pattern in B_PATTERNS else C_PATTERNS
        for run in self.runs:
            if run.pattern in family:
                return self.mounts[run.mount]
        mounts = list(self.mounts.values())
        want_zero = pattern in B_PATTERNS
        return next((m for m in mounts if (m.R_C == 0) == want_zero), mounts[0])

    def reading_choices(self) -> list[Run]:
        """The measured runs whose reading was a choice (they name an ``alternative_convention``), in file order."""
        return [run for run in self.runs if run.alternative_convention]


@dataclass(frozen=True)
class Gap:
    """Something a valid campaign leaves out that some of its analyses need (one verdict for every command).

    The campaign is loaded and every analysis that does not need it runs; one that does raises :meth:`error`, and a
    command that can go on without such a part says :meth:`skipped`.  ``key`` is where it would be given,
    ``what`` what is missing, ``needed_by`` the analyses that need it, ``fix`` what to add (with the value that
    would be assumed, never assumed silently).
    """

    key: str
    what: str
    needed_by: str
    fix: str

    def error(self, source: str) -> InputError:
        """The one-line error of an analysis that cannot run without it."""
        return InputError(source, self.key, f"missing: {self.what}, and {self.needed_by} need it; {self.fix}")

    def reason(self) -> str:
        """What is missing, where and what to add."""
        return f"{self.what} ({self.key}; {self.fix})"

    def skipped(self, part: str) -> str:
        """The sentence of a command that goes on without ``part``."""
        return f"{part} skipped: {self.reason()}."


@dataclass
class ProbeRun:
    """A touch-probe run (``[[probe.runs]]``, SPEC §19; a plug-in's campaign keys read into the same at read time):
    a fixed sphere probed at indexed positions of one or more rotary axes, the measurement of the controller cycles
    that calibrate kinematics.

    ``id`` owns the run's sphere and datum terms (runs of one id share them: one sphere read with several styli);
    ``stylus`` a stylus of :attr:`Probe.styli`; ``sphere`` (3,) the sphere's nominal centre at the home pose, on the
    workpiece side, mm; ``angles`` {axis letter: (a,)} rad, position i is the i-th entry of each (axes not named are
    at 0); ``centres`` (r, a, 3) the commanded X, Y, Z at which the stylus centre reached the sphere's centre, mm;
    ``centre_cov`` (r, a, 3, 3) mm² where the centres were fitted through DPRNT points (``dprnt``, one file per
    position), else None.

    What its campaign format states about the run beyond that (defaults: the engine's ``[[probe.runs]]``):
    ``origin`` (3,) mm, the model frame's origin in the reading frame, NaN where unknown (the frame is then placed at
    the run's first reading and its datum terms carry the rest; None: the machine frame, zeros); ``sphere_terms``
    and ``datum_terms`` the nuisance terms of its sphere's placement and of where the sphere is in the reading frame;
    ``stylus_terms`` those of its stylus (None: the machine's, :func:`~mtmcal_bayes.machines.probe_terms.stylus_terms`);
    ``key`` the type of its observations' keys (None: the engine's) and ``labels`` (a,) the value naming each
    position in them (None: its number from 1); ``section`` the sub-table of ``[probe]`` of a plug-in's it was read
    from and is written back to (None: ``[[probe.runs]]``, the engine's)."""

    id: str
    stylus: str
    sphere: np.ndarray
    angles: dict[str, np.ndarray]
    centres: np.ndarray
    dprnt: list[str] | None = None
    centre_cov: np.ndarray | None = None
    origin: np.ndarray | None = None
    sphere_terms: tuple[str, ...] = SPHERE_TERMS
    datum_terms: tuple[str, ...] = ()
    stylus_terms: tuple[str, ...] | None = None
    key: type | None = None
    labels: np.ndarray | None = None
    section: str | None = None

    @property
    def positions(self) -> int:
        return self.centres.shape[1]

    @property
    def angles_deg(self) -> dict[str, np.ndarray]:
        """The rotary axes' positions {letter: (a,)}, degrees."""
        return {a: units.from_internal(v, "deg") for a, v in self.angles.items()}

    def replace_centres(self, centres: np.ndarray) -> None:
        """Readings ``centres`` (r, a, 3), mm, given directly: the DPRNT files and fit covariances of the old ones
        dropped."""
        self.centres, self.centre_cov, self.dprnt = centres, None, None


@dataclass
class Probe:
    """A campaign's touch probe: its instrument, repeatability (mm), styli and runs, whatever format it was read from.

    ``styli`` {id: programmed length, mm}: from the spindle's ``point_mm`` to the stylus-ball centre, or to its tip
    where ``ball_radii`` gives the ball's radius (mm); ``runs`` in the order of the probe models' positions;
    ``missing`` what the readings leave out that some analyses need (:meth:`gaps`); ``own`` the record a plug-in
    keeps of its campaign format's probe sections (the thesis': the keys of its C-axis and B-axis runs, for
    its own identification and for writing the campaign back), opaque to the engine."""

    instrument: str = ""
    repeatability: float | None = None  # mm
    runs: list[ProbeRun] = field(default_factory=list)
    styli: dict[str, float] = field(default_factory=dict)
    ball_radii: dict[str, float] = field(default_factory=dict)
    missing: list[Gap] = field(default_factory=list)
    own: object | None = None

    def gaps(self) -> list[Gap]:
        """What the probe's readings leave out that its likelihood needs (as its campaign format states it)."""
        return list(self.missing)

    def centre_length(self, stylus: str) -> float:
        """The length of ``stylus`` from the spindle's ``point_mm`` to its ball's centre, mm."""
        return self.styli[stylus] - self.ball_radii.get(stylus, 0.0)

    def dprnt_files(self) -> list[str]:
        """The DPRNT files its runs name, in run order."""
        return [name for run in self.runs for name in (run.dprnt or [])]

    def nuisance_terms(self, desc: MachineDescription | None) -> list[tuple[str, str]]:
        """The probe's nuisance parameters as ``(owner, base)`` pairs (:func:`~.machines.probe_terms.probe_terms`)."""
        return probe_terms(desc, self)


#: how an R-test run's readings are read (SPEC §22): in the sensors' frame carried by the spindle, or turned back
#: by the device's software with the nominal rotation
RTEST_FRAMES = ("tool", "machine")
#: where an R-test run's sensors were zeroed: at its first position (a free zero per run), or absolutely
RTEST_ZEROS = ("first", "absolute")
#: the prior sds of the R-test's nuisance terms where ``[rtest]`` states none, µm (SPEC §22)
RTEST_PRIOR_SD_UM = {"placement_um": 50.0, "nest_length_um": 10.0, "nest_offset_um": 10.0}


@dataclass
class RTestNest:
    """An R-test nest (``[rtest.nests.<id>]``): ``length`` mm from the spindle's ``point_mm`` to the nest centre,
    along the spindle; ``calibrated``: its length and centre are known (no nuisance terms)."""

    length: float
    calibrated: bool = False


@dataclass
class RTestRun:
    """An R-test run (``[[rtest.runs]]``, SPEC §22): the sphere at ``sphere`` (3,) mm (its nominal centre at the
    home pose, workpiece side), read by the sensors of ``nest`` at the positions ``angles`` {axis letter: (a,)} rad
    (axes not named at 0), the linear axes commanded through the nominal chain to put the nest centre on the
    sphere; ``displacements`` (r, a, 3) mm, sphere − nest, in the reading ``frame`` (:data:`RTEST_FRAMES`), zeroed
    as ``zero`` says (:data:`RTEST_ZEROS`); ``placement`` the sphere's placement it shares with other runs (None:
    the runs with an equal ``sphere`` share one, :meth:`RTest.placement_of`)."""

    id: str
    nest: str
    sphere: np.ndarray
    angles: dict[str, np.ndarray]
    displacements: np.ndarray
    frame: str = "tool"
    zero: str = "first"
    placement: str | None = None

    @property
    def positions(self) -> int:
        return self.displacements.shape[1]

    @property
    def angles_deg(self) -> dict[str, np.ndarray]:
        """The rotary axes' positions {letter: (a,)}, degrees."""
        return {a: units.from_internal(v, "deg") for a, v in self.angles.items()}


@dataclass
class RTest:
    """A campaign's R-test (``[rtest]``, SPEC §22): instrument, sensors' repeatability (mm, None: not stated), the
    prior sds of its nuisance terms as stated (mm, None: :data:`RTEST_PRIOR_SD_UM`), nests and runs (none yet: an
    R-test to plan for); ``sphere`` (3,) mm the sphere's nominal centre for runs still to plan (``[rtest] sphere_mm``;
    None: not stated)."""

    instrument: str = ""
    repeatability: float | None = None
    placement_sd: float | None = None
    nest_length_sd: float | None = None
    nest_offset_sd: float | None = None
    nests: dict[str, RTestNest] = field(default_factory=dict)
    runs: list[RTestRun] = field(default_factory=list)
    sphere: np.ndarray | None = None

    def placement_of(self, run: RTestRun) -> str:
        """The placement ``run``'s sphere has: its own ``placement``, else that of the first run with an equal
        ``sphere`` that names none (its id)."""
        if run.placement is not None:
            return run.placement
        return next(r.id for r in self.runs if r.placement is None and np.array_equal(r.sphere, run.sphere))

    def nuisance_terms(self, desc: MachineDescription) -> list[tuple[str, str]]:
        """The R-test's nuisance parameters as ``(owner, base)`` pairs (:func:`~.machines.probe_terms.rtest_terms`)."""
        return rtest_terms(desc, self)

    def prior_sds(self) -> dict[str, float]:
        """The prior sd (mm) of each nuisance base of the R-test, as ``[rtest]`` states it (else SPEC §22's)."""
        sd = {k: units.to_internal(v, "um") for k, v in RTEST_PRIOR_SD_UM.items()}
        place = self.placement_sd if self.placement_sd is not None else sd["placement_um"]
        length = self.nest_length_sd if self.nest_length_sd is not None else sd["nest_length_um"]
        offset = self.nest_offset_sd if self.nest_offset_sd is not None else sd["nest_offset_um"]
        return {"xPR": place, "yPR": place, "zPR": place, "dLR": length, "xNR": offset, "yNR": offset,
                "zNR": offset}


@dataclass
class ReportedValue:
    """A published value (internal units) and the decimals it was printed with."""

    value: float
    unit: str
    decimals: int


@dataclass
class Truth:
    """Known parameter values of a synthetic campaign, internal units; missing = 0."""

    deviations: dict[str, float] = field(default_factory=dict)
    setups: dict[str, dict[str, float]] = field(default_factory=dict)
    mounts: dict[str, dict[str, float]] = field(default_factory=dict)
    probe: dict[str, dict[str, float]] = field(default_factory=dict)  # owner -> {base: value}
    rtest: dict[str, dict[str, float]] = field(default_factory=dict)  # owner -> {base: value}

    def ballbar_part(self) -> Truth:
        """The deviations and the ball-bar nuisance terms."""
        return Truth(self.deviations, self.setups, self.mounts)

    def probe_part(self) -> Truth:
        """The deviations and the touch-probe nuisance terms."""
        return Truth(self.deviations, probe=self.probe)

    def rtest_part(self) -> Truth:
        """The deviations and the R-test's nuisance terms."""
        return Truth(self.deviations, rtest=self.rtest)


@dataclass(frozen=True)
class Tolerance:
    """Tolerance of one quantity, internal units (mm, rad): ``low`` ≤ value ≤ ``high``; None = open
    (a one-sided tolerance).  ``key`` is where it was given (``tolerances.alpha_XB_arcsec``), ``source`` the file
    it was given in ("" for one made in Python)."""

    name: str
    low: float | None
    high: float | None
    key: str = ""
    source: str = ""


def tolerance_text(low, high, unit: str) -> str:
    """``±30 ″``, ``[-20, 50] µm``, ``≤ 20 ″`` or ``≥ -5 µm`` for limits in display units (an open end is None,
    NaN or infinite)."""
    def is_open(v) -> bool:
        return v is None or not math.isfinite(v)

    sym = units.SYMBOL[unit]
    if not (is_open(low) or is_open(high)):
        return f"±{high:g} {sym}" if low == -high else f"[{low:g}, {high:g}] {sym}"
    return f"≤ {high:g} {sym}" if not is_open(high) else f"≥ {low:g} {sym}"


@dataclass
class DesignGoal:
    """What a campaign is designed for (``[design]``, SPEC §16): ``targets`` the standard uncertainty each quantity
    should reach, in display units (″ for angles, µm for lengths: ``parameters.QUANTITIES[name].unit``);
    ``contraction`` the share by which σ_model's uncertainty should shrink (0 < c < 1; None: the planner's
    default); ``budget_min`` the machine minutes available (None: no limit); ``times`` overrides of the
    machine-time model, minutes by name (validated by the planner); ``to_fill_in`` the designed touch-probe and
    R-test runs, the id of each one's table in ``to_fill_in.toml`` -> its name in the design (a run whose id the
    campaign's ``[[probe.runs]]`` / ``[[rtest.runs]]`` hold is measured, the others planned)."""

    targets: dict[str, float] = field(default_factory=dict)
    contraction: float | None = None
    budget_min: float | None = None
    times: dict[str, float] = field(default_factory=dict)
    to_fill_in: dict[str, str] = field(default_factory=dict)


def _chain_frames(ballbar: Ballbar, machine: Machine) -> None:
    """The engine's own: a ball bar's runs read against its machine's chain (a machine without a description has
    none: its runs can be read only in the machine frame, convention "thesis")."""
    if machine.description is not None:
        ballbar.pattern_frames = functools.partial(chain_frame, machine.description)


@dataclass
class Campaign:
    machine: Machine
    ballbar: Ballbar
    probe: Probe | None = None
    reported: dict[str, dict[str, ReportedValue]] = field(default_factory=dict)
    priors: dict[str, dict] = field(default_factory=dict)  # name -> {"dist", params in internal units}
    truth: Truth | None = None
    source: str = "<campaign>"
    base_dir: Path | None = None
    tolerances: dict[str, Tolerance] = field(default_factory=dict)  # by the machine's quantity names
    date: datetime.datetime | None = None  # when the campaign was measured (a TOML date is taken at 00:00)
    temperature_C: float | None = None  # workshop temperature during the campaign, °C
    design: DesignGoal | None = None  # what the campaign was designed for ([design]), if it was
    rtest: RTest | None = None  # its R-test ([rtest]), if it has one

    def __post_init__(self) -> None:
        """A campaign built in Python gets what a read one has: its runs' reading frames from its machine's chain
        and, where its machine's plug-in reads a format of its own, that format in the engine's terms (the thesis':
        its patterns' arcs and bar sides, ``plugins/thesis/translation.py``)."""
        if self.ballbar.pattern_frames is None:
            complete = provided(self.machine, "complete_ballbar", _chain_frames)
            complete(self.ballbar, self.machine)

    def lacking_data(self) -> list[str]:
        """One line per planned run, in measuring order: ``"1. BX@RB1/B, 3 repeats (why)"``."""
        return [f"{k}. {run.describe()}" for k, run in enumerate(self.ballbar.planned, start=1)]

    def lacking_data_note(self) -> str:
        """One sentence naming the planned runs that still lack data ("" when none is planned)."""
        planned = self.ballbar.planned
        if not planned:
            return ""
        n = len(planned)
        return (f"{n} planned run{'s' if n != 1 else ''} still lack{'s' if n == 1 else ''} data and "
                f"{'are' if n != 1 else 'is'} not used: " + "; ".join(self.lacking_data()))

    def require_measured_runs(self) -> None:
        """An :class:`~mtmcal_bayes.errors.InputError` (the file, key ``ballbar.runs``) when the campaign has no
        measured run of either instrument: a campaign designed but not yet measured, or a machine with set-ups
        only."""
        if self.ballbar.runs or self.has_probe_readings() or self.has_rtest_readings():
            return
        n = len(self.ballbar.planned)
        if n:
            msg = (f"no measured runs: {n} planned run{'s' if n != 1 else ''} lack{'s' if n == 1 else ''} data "
                   f"({', '.join(r.label for r in self.ballbar.planned)}); fill them in (give the eccentricities or "
                   "trace_csv, delete planned and repeats) or run simulate to fill them with synthetic data")
        else:
            msg = ("no measured runs: the campaign has set-ups and mounts but no [[ballbar.runs]]; add the measured "
                   "runs (or plan them with design, then fill them in or run simulate)")
        raise InputError(self.source, "ballbar.runs", msg)

    def gaps(self) -> list[Gap]:
        """What this (valid) campaign leaves out that some analyses need; empty for a complete campaign."""
        return self.probe.gaps() if self.probe is not None else []

    def probe_gap(self) -> Gap | None:
        """The first gap that keeps the touch-probe likelihood from running on this campaign, or None."""
        return next(iter(self.probe.gaps()), None) if self.probe is not None else None

    def alternative_reading(self) -> Campaign | None:
        """The campaign read the other way where its reading was a choice: a copy whose runs with an
        ``alternative_convention`` are read in it (and record no choice), everything else shared with this one; None
        when no measured run names an alternative (docs/campaign-format.md, "Readings chosen over another")."""
        bb = self.ballbar
        if not bb.reading_choices():
            return None
        runs = [dataclasses.replace(run, convention=run.alternative_convention, alternative_convention=None)
                if run.alternative_convention else run for run in bb.runs]
        return dataclasses.replace(self, ballbar=dataclasses.replace(bb, runs=runs, alternative_reason=""))

    def has_probe_readings(self) -> bool:
        """Whether the campaign has touch-probe readings (a probe run)."""
        return self.probe is not None and bool(self.probe.runs)

    def has_rtest_readings(self) -> bool:
        """Whether the campaign has R-test readings (an R-test run)."""
        return self.rtest is not None and bool(self.rtest.runs)

    def runs_of(self, pattern: str) -> list[Run]:
        return [r for r in self.ballbar.runs if r.pattern == pattern]

    def primary_setup(self) -> Setup:
        """The tool setup of the first BX run (the thesis' R_B), else the first setup; an
        :class:`~mtmcal_bayes.errors.InputError` naming ``ballbar.setups`` when the campaign has none (a probe-only
        campaign: the ball-bar runs a planner would add start from a set-up)."""
        bb = self.ballbar
        for run in bb.runs:
            if run.pattern == "BX":
                return bb.setups[run.setup]
        if not bb.setups:
            raise InputError(self.source, "ballbar.setups", "no ball-bar set-up: the ball-bar runs to plan start from "
                             "one; give [ballbar] length_mm, a [ballbar.setups.<id>] and a [ballbar.mounts.<id>]")
        return next(iter(bb.setups.values()))

    def mount_for(self, pattern: str) -> Mount:
        """:meth:`Ballbar.mount_for` of the campaign's ball bar."""
        return self.ballbar.mount_for(pattern)
