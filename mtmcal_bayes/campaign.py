"""A calibration campaign as plain dataclasses: machine, ball-bar setups, mounts and runs, probe data.

Values are in internal units (mm, rad).  Files are read and written by
:mod:`mtmcal_bayes.io` (``load_campaign``, ``save_campaign``, format
``mtmcal-campaign/1``, see ``docs/campaign-format.md``); a campaign built in
Python is used the same way.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .patterns import B_PATTERNS, C_PATTERNS


@dataclass
class Machine:
    name: str = ""
    configuration: str = ""
    travel: dict[str, float] = field(default_factory=dict)  # axis letter -> travel, mm


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


@dataclass
class Run:
    """One ball-bar run: pattern, setup, mount and the repeats of each component (mm)."""

    pattern: str
    setup: str
    mount: str
    repeats: dict[str, np.ndarray] = field(default_factory=dict)  # "ex" -> (r,) mm
    trace_csv: list[str] | None = None  # trace files as written in the campaign, one repeat each
    trace_rms: list[dict[str, float]] | None = None  # fit rms per file and direction, mm

    def mean(self, component: str) -> float:
        """Mean of the repeats of ``component``, mm."""
        return float(np.mean(self.repeats[component]))

    @property
    def label(self) -> str:
        return f"{self.pattern}@{self.setup}/{self.mount}"


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


@dataclass
class CAxisProbe:
    """Sphere centres measured at several C angles (thesis Table 5.2), mm."""

    R_C: float
    Z_C: float
    axis_xy: np.ndarray  # (2,) nominal C-axis centreline in machine X, Y
    angles_deg: np.ndarray  # (a,)
    centres: np.ndarray  # (r, a, 3)


@dataclass
class Stylus:
    id: str
    R_B: float
    nominal: np.ndarray  # (2, 3) nominal centre readings at B = 0, 90 deg
    centres: np.ndarray  # (r, 2, 3)


@dataclass
class BAxisProbe:
    X_T: float
    angles_deg: np.ndarray  # (2,)
    styli: dict[str, Stylus] = field(default_factory=dict)


@dataclass
class Probe:
    instrument: str = ""
    repeatability: float | None = None  # mm
    c_axis: CAxisProbe | None = None
    b_axis: BAxisProbe | None = None


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

    def runs_of(self, pattern: str) -> list[Run]:
        return [r for r in self.ballbar.runs if r.pattern == pattern]

    def primary_setup(self) -> Setup:
        """The tool setup of the first BX run (the thesis' R_B), else the first setup."""
        bb = self.ballbar
        for run in bb.runs:
            if run.pattern == "BX":
                return bb.setups[run.setup]
        return next(iter(bb.setups.values()))

    def mount_for(self, pattern: str) -> Mount:
        """The mount the campaign uses for patterns of the same axis (B or C) as ``pattern``, else a
        sensible one: the first with R_C = 0 for B patterns, with R_C > 0 for C patterns."""
        bb = self.ballbar
        family = B_PATTERNS if pattern in B_PATTERNS else C_PATTERNS
        for run in bb.runs:
            if run.pattern in family:
                return bb.mounts[run.mount]
        mounts = list(bb.mounts.values())
        want_zero = pattern in B_PATTERNS
        return next((m for m in mounts if (m.R_C == 0) == want_zero), mounts[0])
