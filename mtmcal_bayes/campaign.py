"""Calibration campaigns: dataclasses, TOML loading with validation, saving.

A campaign file (``format = "mtmcal-campaign/1"``, see ``docs/campaign-format.md``)
describes one calibration: the machine, the ball-bar setups, mounts and runs,
touch-probe data, published results, optional priors and, for synthetic
campaigns, the truth.  :func:`load_campaign` reads and validates it; every
problem is an :class:`~mtmcal_bayes.errors.InputError` naming the file and the
key.  Values are held in internal units (mm, rad) and converted back by
:func:`save_campaign`.
"""

from __future__ import annotations

import math
import os
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import units
from .errors import InputError
from .models.patterns import CR_GEOMETRIES
from .parameters import DEVIATIONS, MOUNT_NUISANCE, QUANTITIES, SETUP_NUISANCE
from .patterns import COMPONENTS, PATTERNS, mount_conflict
from .textfiles import read_text, write_text_atomic
from .tomlio import Fixed, dumps, printed_decimals
from .traces import read_trace

FORMAT = "mtmcal-campaign/1"
PRIOR_DISTS = {"normal": ("sd",), "halfnormal": ("sd",), "uniform": ("low", "high")}


# --------------------------------------------------------------------------- dataclasses
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


# --------------------------------------------------------------------------- reading helpers
_MISSING = object()

class TomlReader:
    """Typed access to a parsed TOML document with errors naming file and key."""

    def __init__(self, source: str):
        self.source = source

    def fail(self, key: str | None, message: str):
        raise InputError(self.source, key, message)

    def _lookup(self, table: dict, key: str, path: str, required: bool, what: str):
        """``(full key, value)``; value ``_MISSING`` when absent and not required."""
        full = f"{path}.{key}" if path else key
        if key not in table:
            if required:
                self.fail(full, f"missing {what}".rstrip())
            return full, _MISSING
        return full, table[key]

    def table(self, parent: dict, key: str, path: str, required: bool = True) -> dict | None:
        full, v = self._lookup(parent, key, path, required, "table")
        if v is _MISSING:
            return None
        if not isinstance(v, dict):
            self.fail(full, f"expected a table, got {_kind(v)}")
        return v

    def subtables(self, parent: dict, key: str, path: str, allowed, what: str):
        """Yield ``(id, full key, table)`` for each ``[path.key.<id>]``; at least one is required."""
        tables = self.table(parent, key, path)
        if not tables:
            self.fail(f"{path}.{key}", f"at least one {what} is needed")
        for oid, sub in tables.items():
            full = f"{path}.{key}.{oid}"
            if not isinstance(sub, dict):
                self.fail(full, f"expected a table, got {_kind(sub)}")
            self.check_keys(sub, allowed, full)
            yield oid, full, sub

    def check_keys(self, table: dict, allowed, path: str) -> None:
        for k in table:
            if k not in allowed:
                where = f"{path}.{k}" if path else k
                self.fail(where, f"unknown key (expected one of: {', '.join(sorted(allowed))})")

    def string(self, table: dict, key: str, path: str, required: bool = False, default: str = "") -> str:
        full, v = self._lookup(table, key, path, required, "")
        if v is _MISSING:
            return default
        if not isinstance(v, str):
            self.fail(full, f"expected a string, got {_kind(v)}")
        return v

    def number(self, table: dict, key: str, path: str, *, required: bool = True, positive: bool = False,
               nonnegative: bool = False, default: float | None = None) -> float | None:
        full, v = self._lookup(table, key, path, required, "")
        if v is _MISSING:
            return default
        return self._check_number(v, full, positive, nonnegative)

    def _check_number(self, v, full: str, positive: bool = False, nonnegative: bool = False) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            self.fail(full, f"expected a number, got {_kind(v)}")
        v = float(v)
        if math.isnan(v):
            self.fail(full, "NaN is not a valid value")
        if math.isinf(v):
            self.fail(full, "infinite value")
        if positive and v <= 0:
            self.fail(full, f"must be positive, got {v:g}")
        if nonnegative and v < 0:
            self.fail(full, f"must not be negative, got {v:g}")
        return v

    def array(self, table: dict, key: str, path: str, shape: tuple, *, required: bool = True) -> np.ndarray | None:
        """Numeric array of the given shape; ``None`` entries in ``shape`` match any length >= 1."""
        full, v = self._lookup(table, key, path, required, "")
        if v is _MISSING:
            return None
        out = self._nested(v, full, len(shape))
        arr = np.array(out, dtype=float)
        if arr.ndim != len(shape) or any(s is not None and s != n for s, n in zip(shape, arr.shape)):
            want = " x ".join("n" if s is None else str(s) for s in shape)
            self.fail(full, f"expected an array of shape {want}, got {' x '.join(map(str, arr.shape)) or 'a scalar'}")
        if arr.size == 0:
            self.fail(full, "empty array")
        return arr

    def _nested(self, v, full: str, depth: int):
        if depth == 0:
            return self._check_number(v, full)
        if not isinstance(v, list):
            self.fail(full, f"expected an array, got {_kind(v)}")
        if not v:
            self.fail(full, "empty array")
        items = [self._nested(x, f"{full}[{i}]", depth - 1) for i, x in enumerate(v)]
        if depth > 1 and len({len(x) for x in items}) > 1:
            self.fail(full, "rows of different lengths")
        return items


def _kind(v) -> str:
    if isinstance(v, bool):
        return "a boolean"
    if isinstance(v, (int, float)):
        return "a number"
    if isinstance(v, str):
        return f"the string {v!r}"
    if isinstance(v, list):
        return "an array"
    if isinstance(v, dict):
        return "a table"
    return type(v).__name__


# --------------------------------------------------------------------------- loading
def load_campaign(path: str | os.PathLike | None = None) -> Campaign:
    """Load and validate a campaign TOML file; ``None`` loads the built-in thesis campaign.

    Raises :class:`~mtmcal_bayes.errors.InputError` (one line: file, key, problem)
    for a missing, empty or malformed file or any invalid content.
    """
    if path is None:
        from .datasets import builtin_campaign_text

        text, source = builtin_campaign_text()
        return parse_campaign(text, source=source, base_dir=None)
    p = Path(path)
    text = read_text(p, "campaign file")
    return parse_campaign(text, source=str(p), base_dir=p.parent)


def parse_campaign(text: str, source: str = "<campaign>", base_dir: Path | None = None) -> Campaign:
    """Parse and validate campaign TOML ``text``; ``source`` names it in error messages."""
    r = TomlReader(source)
    if not text.strip():
        r.fail(None, "empty file (expected a campaign TOML with format = \"mtmcal-campaign/1\")")
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        r.fail(None, f"malformed TOML: {exc}")
    r.check_keys(doc, {"format", "machine", "ballbar", "probe", "reported", "priors", "truth"}, "")
    fmt = r.string(doc, "format", "", required=True)
    if fmt != FORMAT:
        r.fail("format", f"unknown format {fmt!r} (this version reads {FORMAT!r})")

    machine = _machine(r, r.table(doc, "machine", "", required=False) or {})
    ballbar = _ballbar(r, r.table(doc, "ballbar", ""), base_dir)
    probe_t = r.table(doc, "probe", "", required=False)
    probe = _probe(r, probe_t) if probe_t is not None else None
    reported = _reported(r, r.table(doc, "reported", "", required=False) or {}, text)
    priors = _priors(r, r.table(doc, "priors", "", required=False) or {})
    truth_t = r.table(doc, "truth", "", required=False)
    truth = parse_truth(r, truth_t, "truth", ballbar) if truth_t is not None else None
    return Campaign(machine, ballbar, probe, reported, priors, truth, source, base_dir)


def _machine(r: TomlReader, t: dict) -> Machine:
    allowed = {"name", "configuration"} | {f"travel_{a}_mm" for a in "XYZ"}
    r.check_keys(t, allowed, "machine")
    travel = {a: r.number(t, f"travel_{a}_mm", "machine", positive=True)
              for a in "XYZ" if f"travel_{a}_mm" in t}
    return Machine(r.string(t, "name", "machine"), r.string(t, "configuration", "machine"), travel)


def _ballbar(r: TomlReader, t: dict, base_dir: Path | None) -> Ballbar:
    P = "ballbar"
    r.check_keys(t, {"instrument", "length_mm", "accuracy_um", "feed_mm_per_min", "cr_geometry",
                     "setups", "mounts", "runs"}, P)
    cr_geometry = r.string(t, "cr_geometry", P, default="RC-LB")
    if cr_geometry not in CR_GEOMETRIES:
        r.fail(f"{P}.cr_geometry", f"unknown CR geometry {cr_geometry!r} (expected {' or '.join(CR_GEOMETRIES)})")
    length = r.number(t, "length_mm", P, positive=True)
    accuracy = units.to_internal(r.number(t, "accuracy_um", P, positive=True), "um")
    feed = r.number(t, "feed_mm_per_min", P, required=False, positive=True)

    setups: dict[str, Setup] = {}
    for sid, path, s in r.subtables(t, "setups", P, {"R_B_mm", "Z_T_mm", "X_T_mm"}, "tool setup"):
        setups[sid] = Setup(sid, r.number(s, "R_B_mm", path, positive=True),
                            r.number(s, "Z_T_mm", path), r.number(s, "X_T_mm", path))
    _distinct_tool_lengths(r, [(f"{P}.setups.{s.id}", s.R_B, s.Z_T) for s in setups.values()])

    mounts: dict[str, Mount] = {}
    for mid, path, m in r.subtables(t, "mounts", P, {"Z_C_mm", "R_C_mm"}, "W-ball mount"):
        mounts[mid] = Mount(mid, r.number(m, "Z_C_mm", path, nonnegative=True),
                            r.number(m, "R_C_mm", path, nonnegative=True))

    raw_runs = t.get("runs")
    if raw_runs is None:
        r.fail(f"{P}.runs", "missing: at least one [[ballbar.runs]] is needed")
    if not isinstance(raw_runs, list) or not all(isinstance(x, dict) for x in raw_runs) or not raw_runs:
        r.fail(f"{P}.runs", "expected one or more [[ballbar.runs]] tables")
    runs = [_run(r, x, f"{P}.runs[{i}]", setups, mounts, base_dir, length, cr_geometry)
            for i, x in enumerate(raw_runs)]
    return Ballbar(length, accuracy, r.string(t, "instrument", P), feed, setups, mounts, runs, cr_geometry)


def _distinct_tool_lengths(r: TomlReader, items: list[tuple[str, float, float]]) -> None:
    """Two tool lengths that are equal make the second one carry no information."""
    for i, (pa, rb_a, zt_a) in enumerate(items):
        for pb, rb_b, zt_b in items[i + 1:]:
            if rb_a == rb_b:
                r.fail(f"{pb}.R_B_mm", f"equal to {pa}.R_B_mm ({rb_a:g} mm): a second tool length "
                       "equal to the first carries no information")
            if zt_a == zt_b:
                r.fail(f"{pb}.Z_T_mm", f"equal to {pa}.Z_T_mm ({zt_a:g} mm) although R_B differs: "
                       "Z_T + R_B must stay constant between tool lengths")


def _run(r: TomlReader, t: dict, path: str, setups, mounts, base_dir, L_B: float, cr_geometry: str) -> Run:
    allowed = {"pattern", "setup", "mount", "trace_csv"} | {f"{c}_um" for c in ("ex", "ey", "ez")}
    r.check_keys(t, allowed, path)
    pattern = r.string(t, "pattern", path, required=True)
    if pattern not in PATTERNS:
        r.fail(f"{path}.pattern", f"unknown pattern {pattern!r} (expected one of {' '.join(PATTERNS)})")
    setup = r.string(t, "setup", path, required=True)
    if setup not in setups:
        r.fail(f"{path}.setup", f"names setup {setup!r}, which is not in [ballbar.setups] "
               f"(have: {', '.join(setups)})")
    mount = r.string(t, "mount", path, required=True)
    if mount not in mounts:
        r.fail(f"{path}.mount", f"names mount {mount!r}, which is not in [ballbar.mounts] "
               f"(have: {', '.join(mounts)})")
    if conflict := mount_conflict(pattern, mount, mounts[mount].R_C):
        r.fail(f"{path}.mount", conflict)
    repeats = {}
    for c in ("ex", "ey", "ez"):
        key = f"{c}_um"
        if key in t:
            if c not in COMPONENTS[pattern]:
                r.fail(f"{path}.{key}", f"pattern {pattern} has no component {c} "
                       f"(it gives {' and '.join(COMPONENTS[pattern])})")
            repeats[c] = units.to_internal(r.array(t, key, path, (None,)), "um")
            too_big = np.flatnonzero(np.abs(repeats[c]) >= L_B)
            if too_big.size:  # also keeps the models and the planner away from overflow
                i = int(too_big[0])
                r.fail(f"{path}.{key}[{i}]", f"{units.from_internal(repeats[c][i], 'um'):g} µm is not below the "
                       f"bar length L_B = {L_B:g} mm: not an eccentricity")
    traces = rms = None
    if "trace_csv" in t:
        if repeats:
            r.fail(f"{path}.trace_csv", "a run carries either eccentricity repeats or traces, not both")
        raw = t["trace_csv"]
        traces = [raw] if isinstance(raw, str) else raw
        if not isinstance(traces, list) or not traces or not all(isinstance(x, str) and x for x in traces):
            r.fail(f"{path}.trace_csv", "expected a file name or an array of file names")
        extracted, rms = [], []
        for name in traces:
            fpath = (base_dir / name) if base_dir is not None else Path(name)
            if not fpath.exists():
                r.fail(f"{path}.trace_csv", f"trace file {str(fpath)!r} not found")
            if fpath.is_dir():
                r.fail(f"{path}.trace_csv", f"trace file {str(fpath)!r} is a directory")
            ex = read_trace(fpath, pattern, L_B, cr_geometry)
            extracted.append(ex.values)
            rms.append(ex.rms)
        repeats = {c: np.array([e[c] for e in extracted]) for c in COMPONENTS[pattern]}
    if not repeats:
        r.fail(path, f"no eccentricities: give {' and/or '.join(c + '_um' for c in COMPONENTS[pattern])} "
               "or trace_csv")
    return Run(pattern, setup, mount, repeats, traces, rms)


def _probe(r: TomlReader, t: dict) -> Probe:
    P = "probe"
    r.check_keys(t, {"instrument", "repeatability_um", "c_axis", "b_axis"}, P)
    rep = r.number(t, "repeatability_um", P, required=False, positive=True)
    probe = Probe(r.string(t, "instrument", P), units.to_internal(rep, "um") if rep is not None else None)
    c = r.table(t, "c_axis", P, required=False)
    if c is not None:
        path = f"{P}.c_axis"
        r.check_keys(c, {"R_C_mm", "Z_C_mm", "axis_xy_mm", "angles_deg", "centres_mm"}, path)
        angles = r.array(c, "angles_deg", path, (None,))
        probe.c_axis = CAxisProbe(
            r.number(c, "R_C_mm", path, positive=True), r.number(c, "Z_C_mm", path, nonnegative=True),
            r.array(c, "axis_xy_mm", path, (2,)), angles,
            r.array(c, "centres_mm", path, (None, len(angles), 3)))
    b = r.table(t, "b_axis", P, required=False)
    if b is not None:
        path = f"{P}.b_axis"
        r.check_keys(b, {"X_T_mm", "angles_deg", "styli"}, path)
        angles = r.array(b, "angles_deg", path, (2,))
        if list(angles) != [0.0, 90.0]:  # identify's Eqs 5.8–5.19 take the rows as B = 0° and B = 90°
            r.fail(f"{path}.angles_deg", f"must be [0, 90] (the B-axis equations use the centres at B = 0° "
                   f"and 90°), got [{', '.join(f'{a:g}' for a in angles)}]")
        bax = BAxisProbe(r.number(b, "X_T_mm", path), angles)
        for sid, sp, s in r.subtables(b, "styli", path, {"R_B_mm", "nominal_mm", "centres_mm"}, "stylus"):
            bax.styli[sid] = Stylus(sid, r.number(s, "R_B_mm", sp, positive=True),
                                    r.array(s, "nominal_mm", sp, (2, 3)),
                                    r.array(s, "centres_mm", sp, (None, 2, 3)))
        for i, (sa, a) in enumerate(bax.styli.items()):
            for sb, bb in list(bax.styli.items())[i + 1:]:
                if a.R_B == bb.R_B:
                    r.fail(f"{path}.styli.{sb}.R_B_mm", f"equal to styli.{sa}.R_B_mm ({a.R_B:g} mm): "
                           "a second stylus length equal to the first carries no information")
        probe.b_axis = bax
    return probe


def _reported(r: TomlReader, t: dict, text: str) -> dict[str, dict[str, ReportedValue]]:
    out: dict[str, dict[str, ReportedValue]] = {}
    for method, vals in t.items():
        path = f"reported.{method}"
        if not isinstance(vals, dict):
            r.fail(path, f"expected a table, got {_kind(vals)}")
        decimals = printed_decimals(text, path)
        out[method] = {}
        for key in vals:
            name, unit = units.split_unit_key(key)
            q = QUANTITIES.get(name)
            if q is None or unit != q.unit:
                r.fail(f"{path}.{key}", "unknown quantity: expected <name>_arcsec for angles or <name>_um "
                       "for lengths, with a canonical deviation name")
            v = r.number(vals, key, path)
            out[method][name] = ReportedValue(units.to_internal(v, unit), unit, decimals.get(key, 2))
    return out


def _priors(r: TomlReader, t: dict) -> dict[str, dict]:
    known = {**{k: q.unit for k, q in DEVIATIONS.items()},
             **{k: q.unit for k, q in {**SETUP_NUISANCE, **MOUNT_NUISANCE}.items()},
             "sigma_model": "um"}
    out = {}
    for name, spec in t.items():
        path = f"priors.{name}"
        if name not in known:
            r.fail(path, "unknown parameter (expected a deviation name, one of xT yT zT dRB xW yW zW, "
                   "or sigma_model)")
        if not isinstance(spec, dict):
            r.fail(path, "expected an inline table such as {dist = \"normal\", sd_arcsec = 30}")
        dist = r.string(spec, "dist", path, required=True)
        if dist not in PRIOR_DISTS:
            r.fail(f"{path}.dist", f"unknown distribution {dist!r} (expected one of {', '.join(PRIOR_DISTS)})")
        unit = known[name]
        params = PRIOR_DISTS[dist] + (("mean",) if dist == "normal" else ())
        r.check_keys(spec, {"dist"} | {f"{p}_{unit}" for p in params}, path)
        parsed = {"dist": dist}
        for p in params:
            v = r.number(spec, f"{p}_{unit}", path, required=(p != "mean"), positive=(p == "sd"),
                         default=0.0)
            parsed[p] = units.to_internal(v, unit)
        if dist == "uniform" and parsed["high"] <= parsed["low"]:
            r.fail(f"{path}.high_{unit}", "must be greater than low")
        if name == "sigma_model":  # a standard deviation: the sampler only visits sigma_model > 0
            for p in ("low", "mean"):
                if parsed.get(p, 0.0) < 0:
                    r.fail(f"{path}.{p}_{unit}", f"must not be negative for sigma_model (a standard deviation), "
                           f"got {units.from_internal(parsed[p], unit):g}")
        out[name] = parsed
    return out


def parse_truth(r: TomlReader, t: dict, path: str, ballbar: Ballbar) -> Truth:
    """Parse truth tables (``deviations``, ``setups.<id>``, ``mounts.<id>``) located at ``path``."""
    r.check_keys(t, {"deviations", "setups", "mounts"}, path)
    truth = Truth()
    dev = r.table(t, "deviations", path, required=False) or {}
    for key in dev:
        name, unit = units.split_unit_key(key)
        q = DEVIATIONS.get(name)
        if q is None or unit != q.unit:
            r.fail(f"{path}.deviations.{key}", "unknown deviation: expected <name>_arcsec or <name>_um "
                   f"with one of {', '.join(DEVIATIONS)}")
        truth.deviations[name] = units.to_internal(r.number(dev, key, f"{path}.deviations"), unit)
    for group, table, owners in (("setups", SETUP_NUISANCE, ballbar.setups),
                                 ("mounts", MOUNT_NUISANCE, ballbar.mounts)):
        for oid, vals in (r.table(t, group, path, required=False) or {}).items():
            op = f"{path}.{group}.{oid}"
            if oid not in owners:
                r.fail(op, f"no such {group[:-1]} in [ballbar.{group}] (have: {', '.join(owners)})")
            if not isinstance(vals, dict):
                r.fail(op, f"expected a table, got {_kind(vals)}")
            r.check_keys(vals, {f"{k}_um" for k in table}, op)
            getattr(truth, group)[oid] = {k[:-3]: units.to_internal(r.number(vals, k, op), "um") for k in vals}
    return truth


# --------------------------------------------------------------------------- saving
def campaign_to_dict(c: Campaign, save_dir: Path | None = None) -> dict:
    """The TOML document of a campaign (file units), as nested dicts.

    Trace files are written relative to ``save_dir`` (absolute when ``None``).
    """
    um = lambda v: units.from_internal(v, "um")
    doc: dict = {"format": FORMAT}
    doc["machine"] = {"name": c.machine.name, "configuration": c.machine.configuration,
                      **{f"travel_{a}_mm": v for a, v in c.machine.travel.items()}}
    bb = c.ballbar
    b: dict = {}
    if bb.instrument:
        b["instrument"] = bb.instrument
    b["length_mm"] = bb.length
    b["accuracy_um"] = um(bb.accuracy)
    if bb.feed_mm_per_min is not None:
        b["feed_mm_per_min"] = bb.feed_mm_per_min
    if bb.cr_geometry != "RC-LB":
        b["cr_geometry"] = bb.cr_geometry
    b["setups"] = {s.id: {"R_B_mm": s.R_B, "Z_T_mm": s.Z_T, "X_T_mm": s.X_T} for s in bb.setups.values()}
    b["mounts"] = {m.id: {"Z_C_mm": m.Z_C, "R_C_mm": m.R_C} for m in bb.mounts.values()}
    b["runs"] = []
    for run in bb.runs:
        d = {"pattern": run.pattern, "setup": run.setup, "mount": run.mount}
        if run.trace_csv:
            d["trace_csv"] = [str(Path(c.base_dir or ".", f).resolve()) if save_dir is None
                              else os.path.relpath(Path(c.base_dir or ".", f).resolve(), save_dir)
                              for f in run.trace_csv]
        else:
            d.update({f"{k}_um": [um(x) for x in v] for k, v in run.repeats.items()})
        b["runs"].append(d)
    doc["ballbar"] = b
    if c.probe is not None:
        doc["probe"] = _probe_dict(c.probe)
    if c.reported:
        doc["reported"] = {m: {f"{n}_{v.unit}": Fixed(units.from_internal(v.value, v.unit), v.decimals)
                               for n, v in vals.items()} for m, vals in c.reported.items()}
    if c.priors:
        doc["priors"] = {}
        for name, spec in c.priors.items():
            unit = DEVIATIONS[name].unit if name in DEVIATIONS else "um"
            doc["priors"][name] = {"dist": spec["dist"], **{f"{k}_{unit}": units.from_internal(v, unit)
                                                            for k, v in spec.items() if k != "dist"}}
    if c.truth is not None:
        doc["truth"] = truth_to_dict(c.truth)
    return doc


def truth_to_dict(t: Truth) -> dict:
    d: dict = {"deviations": {f"{n}_{DEVIATIONS[n].unit}": units.from_internal(v, DEVIATIONS[n].unit)
                              for n, v in t.deviations.items()}}
    for group in ("setups", "mounts"):
        vals = getattr(t, group)
        if vals:
            d[group] = {oid: {f"{k}_um": units.from_internal(v, "um") for k, v in kv.items()}
                        for oid, kv in vals.items()}
    return d


def _probe_dict(p: Probe) -> dict:
    d: dict = {}
    if p.instrument:
        d["instrument"] = p.instrument
    if p.repeatability is not None:
        d["repeatability_um"] = units.from_internal(p.repeatability, "um")
    if p.c_axis is not None:
        c = p.c_axis
        d["c_axis"] = {"R_C_mm": c.R_C, "Z_C_mm": c.Z_C, "axis_xy_mm": c.axis_xy,
                       "angles_deg": c.angles_deg, "centres_mm": c.centres}
    if p.b_axis is not None:
        b = p.b_axis
        d["b_axis"] = {"X_T_mm": b.X_T, "angles_deg": b.angles_deg,
                       "styli": {s.id: {"R_B_mm": s.R_B, "nominal_mm": s.nominal, "centres_mm": s.centres}
                                 for s in b.styli.values()}}
    return d


def save_campaign(campaign: Campaign, path: str | os.PathLike, header: str | None = None) -> None:
    """Write ``campaign`` as TOML to ``path`` (atomically); ``header`` becomes a leading comment."""
    text = dumps(campaign_to_dict(campaign, Path(path).resolve().parent))
    if header:
        text = "".join(f"# {line}\n" for line in header.splitlines()) + "\n" + text
    write_text_atomic(path, text)
