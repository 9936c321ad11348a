"""Reading campaign TOML files (``mtmcal-campaign/1``) with validation, and truth files.

A campaign file (see ``docs/campaign-format.md``) describes one calibration:
the machine, the ball-bar setups, mounts and runs, touch-probe data, published
results, optional priors and, for synthetic campaigns, the truth.
:func:`load_campaign` reads and validates it into the dataclasses of
:mod:`mtmcal_bayes.campaign` (internal units, mm and rad); every problem is an
:class:`~mtmcal_bayes.errors.InputError` naming the file and the key.
"""

from __future__ import annotations

import dataclasses
import datetime
import os
from pathlib import Path

import numpy as np

from .. import units
from ..campaign import (
    Ballbar,
    BAxisProbe,
    Campaign,
    CAxisProbe,
    DesignGoal,
    Machine,
    Mount,
    PlannedRun,
    Probe,
    ReportedValue,
    Run,
    Setup,
    Stylus,
    Truth,
)
from ..conventions import (
    CONVENTIONS,
    ConventionError,
    check_convention_name,
    check_run,
    run_convention,
    run_matrix,
)
from ..datasets import builtin_campaign_text, data_path
from ..errors import InputError, MtmcalError
from ..parameters import (
    DEVIATIONS,
    DISCREPANCY_SCALES,
    MOUNT_NUISANCE,
    PROBE_NUISANCE,
    QUANTITIES,
    SETUP_NUISANCE,
)
from ..patterns import COMPONENTS, CR_GEOMETRIES, PATTERNS, mount_conflict
from ..sphere import fit_sphere
from ..machines.deviations import quantities as deviation_table
from ..machines.plugins import provided
from ..machines.probe_terms import probe_terms
from .measurement_sections import described_ballbar, described_probe
from .planned_runs import PLANNED_KEYS as PLANNED_RUN_KEYS
from .planned_runs import planned_in_order, planned_run
from .dprnt import read_dprnt
from .machine_reader import BUILTIN_TYPES, DESCRIPTION_KEYS, parse_description, referenced_description
from .textfiles import read_user_text
from .tolerances import machine_names, parse_tolerances
from .toml_reader import TomlReader, kind_of, parse_toml
from .tomlio import printed_decimals
from .traces import read_trace

FORMAT = "mtmcal-campaign/1"
#: the discrepancy scales a [priors] entry may name (sigma_model, sigma_model_probe)
SCALES = tuple(q.name for q in DISCREPANCY_SCALES.values())
PRIOR_DISTS = {"normal": ("sd",), "halfnormal": ("sd",), "uniform": ("low", "high")}
#: largest |number| of a [priors] entry, in its unit (1°, 10 mm): no geometric deviation or offset of a working
#: machine tool comes near it, and numbers like 1e20 break the linear algebra (docs/campaign-format.md)
PRIOR_LIMIT = {"arcsec": (3600.0, "1°"), "um": (10_000.0, "10 mm")}
#: narrowest prior sd (or uniform width), in its unit: below it the parameter is fixed beneath the models'
#: floating-point resolution (an sd of 1e-300 gives NaN)
PRIOR_RESOLUTION = 1e-3
#: the keys of a run's data: a planned run has none of them
DATA_KEYS = ("ex_um", "ey_um", "ez_um", "trace_csv")
#: the keys only a planned run (``planned = true``) has
PLANNED_KEYS = (*PLANNED_RUN_KEYS, "length_mm")


# --------------------------------------------------------------------------- loading
def load_campaign(path: str | os.PathLike | None = None) -> Campaign:
    """Load and validate a campaign TOML file; ``None`` loads the built-in thesis campaign.

    Raises :class:`~mtmcal_bayes.errors.InputError` (one line: file, key, problem)
    for a missing, empty or malformed file or any invalid content.
    """
    if path is None:
        text, source = builtin_campaign_text()
        return parse_campaign(text, source=source, base_dir=None)
    p = Path(path)
    text = read_user_text(p, "campaign file")
    return parse_campaign(text, source=str(p), base_dir=p.parent)


def parse_campaign(text: str, source: str = "<campaign>", base_dir: Path | None = None) -> Campaign:
    """Parse and validate campaign TOML ``text``; ``source`` names it in error messages."""
    r = TomlReader(source)
    doc = parse_toml(text, source, f"a campaign TOML with format = \"{FORMAT}\"")
    r.check_keys(doc, {"format", "machine", "ballbar", "probe", "reported", "priors", "truth", "tolerances", "date",
                       "temperature_C", "design"}, "")
    fmt = r.string(doc, "format", "", required=True)
    if fmt != FORMAT:
        r.fail("format", f"unknown format {fmt!r} (this version reads {FORMAT!r})")

    machine = _machine(r, doc.get("machine"), base_dir)
    read_sections = provided(machine, "campaign_sections", measurement_sections)  # a plug-in's campaign keys
    ballbar, probe = read_sections(r, doc, machine, base_dir)
    deviations = deviation_quantities(machine)
    reported = _reported(r, r.table(doc, "reported", "", required=False) or {}, text)
    priors = _priors(r, r.table(doc, "priors", "", required=False) or {}, deviations)
    truth_t = r.table(doc, "truth", "", required=False)
    truth = parse_truth(r, truth_t, "truth", ballbar, probe=probe, machine=machine) if truth_t is not None else None
    tolerances = parse_tolerances(r, r.table(doc, "tolerances", "", required=False) or {},
                                  names=machine_names(machine))
    temperature = r.number(doc, "temperature_C", "", required=False)
    if temperature is not None and not -50.0 <= temperature <= 100.0:
        r.fail("temperature_C", f"{temperature:g} °C is not a workshop temperature (−50 to 100 °C)")
    design_t = r.table(doc, "design", "", required=False)
    design = _design(r, design_t, provided(machine, "quantity_table", deviations)) if design_t is not None else None
    return Campaign(machine, ballbar, probe, reported, priors, truth, source, base_dir, tolerances,
                    _date(r, doc), temperature, design)


def measurement_sections(r: TomlReader, doc: dict, machine: Machine, base_dir: Path | None) -> tuple[Ballbar, Probe]:
    """``[ballbar]`` and ``[probe]`` of a campaign of any described machine: set-ups, mounts (the W ball's
    ``position_mm``), runs ``<axis><R|T|A|X|Y|Z>`` with ``arc_deg`` and ``hold_deg``, ``[[probe.runs]]``."""
    desc = machine.description
    probe_t = r.table(doc, "probe", "", required=False)
    ballbar = described_ballbar(r, r.table(doc, "ballbar", "", required=False), desc)
    probe = described_probe(r, probe_t, desc) if probe_t is not None else None
    if not ballbar.runs and not ballbar.planned and probe is None and not (ballbar.setups and ballbar.mounts):
        r.fail("ballbar", "no measurements: give [[ballbar.runs]] or [[probe.runs]] (or, for a machine to design "
               "a campaign for, its [ballbar.setups] and [ballbar.mounts])")
    if "reported" in doc:
        r.fail("reported", "not read for a described machine yet (docs/machines.md)")
    return ballbar, probe


def thesis_sections(r: TomlReader, doc: dict, machine: Machine, base_dir: Path | None) -> tuple[Ballbar, Probe]:
    """``[ballbar]`` and ``[probe]`` in the thesis' campaign format (its lever arms R_B, Z_T, X_T, Z_C, R_C; the
    probe's ``[probe.c_axis]`` and ``[probe.b_axis]``, thesis Tables 4.2–4.4, 5.1–5.2): the thesis plug-in's keys."""
    probe_t = r.table(doc, "probe", "", required=False)
    ballbar = _ballbar(r, r.table(doc, "ballbar", ""), base_dir)
    return ballbar, _probe(r, probe_t, base_dir) if probe_t is not None else None


def _machine(r: TomlReader, t, base_dir: Path | None) -> Machine:
    """``[machine]``: the thesis format (name, configuration, travels: the thesis machine), a description (SPEC
    §19: ``[machine.axes]``, ``[machine.spindle]``, ...) or ``description = "<type or file>"`` beside name, serial and
    type; or ``machine = "<type or file>"`` alone."""
    if isinstance(t, str):
        desc = referenced_description(t, r.source, "machine", base_dir)
        return Machine(desc.name, desc.configuration, description=desc)
    if t is None:
        t = {}
    if not isinstance(t, dict):
        r.fail("machine", f"expected a table or a machine type / description file name, got {kind_of(t)}")
    legacy = {"name", "configuration", "serial", "type"} | {f"travel_{a}_mm" for a in "XYZ"}
    allowed = legacy | DESCRIPTION_KEYS | {"description"}
    r.check_keys(t, allowed, "machine")
    travel = {a: r.number(t, f"travel_{a}_mm", "machine", positive=True)
              for a in "XYZ" if f"travel_{a}_mm" in t}
    serial, mtype = r.string(t, "serial", "machine").strip(), r.string(t, "type", "machine").strip()
    if "description" in t:
        extra = sorted(set(t) & (DESCRIPTION_KEYS - {"name"}))
        if extra:
            r.fail(f"machine.{extra[0]}", "the machine is described by machine.description; describe it there or "
                   "here, not both")
        desc = referenced_description(r.string(t, "description", "machine"), r.source, "machine.description",
                                      base_dir)
        return Machine(r.string(t, "name", "machine") or desc.name, desc.configuration, travel, serial, mtype, desc)
    if set(t) & (DESCRIPTION_KEYS - {"name", "configuration"}):
        desc = parse_description(t, r.source, "machine", extra_keys=frozenset(legacy))
        return Machine(desc.name, desc.configuration, travel, serial, mtype, desc)
    configuration = r.string(t, "configuration", "machine")
    if configuration and configuration.replace(" ", "") != THESIS_CONFIGURATION:
        r.fail("machine.configuration", f"{configuration!r} is not the thesis machine's ({THESIS_CONFIGURATION}) and "
               "nothing describes it: add [machine.axes.<letter>] and [machine.spindle] (docs/machines.md) or name a "
               f"built-in type with description = \"...\" ({', '.join(BUILTIN_TYPES)})")
    return Machine(r.string(t, "name", "machine"), configuration, travel, serial, mtype)


def deviation_quantities(machine: Machine) -> dict:
    """The deviations a campaign on ``machine`` can name: its plug-in's names where it has them (the thesis' 13),
    else the description's."""
    names = provided(machine, "deviation_table")
    return dict(names) if names is not None else deviation_table(machine.description)


def _date(r: TomlReader, doc: dict) -> datetime.datetime | None:
    """The campaign's ``date``: a TOML date (taken at 00:00) or local date-time; an offset is kept."""
    if "date" not in doc:
        return None
    v = doc["date"]
    if isinstance(v, datetime.datetime):
        return v
    if isinstance(v, datetime.date):
        return datetime.datetime(v.year, v.month, v.day)
    r.fail("date", f"expected a TOML date such as 2026-03-15 or a date-time 2026-03-15T08:30:00, got {kind_of(v)}")


def _ballbar(r: TomlReader, t: dict, base_dir: Path | None) -> Ballbar:
    P = "ballbar"
    r.check_keys(t, {"instrument", "length_mm", "accuracy_um", "feed_mm_per_min", "cr_geometry", "convention",
                     "alternative_reason", "setups", "mounts", "runs"}, P)
    convention = r.string(t, "convention", P, default="thesis")
    if convention not in CONVENTIONS:
        r.fail(f"{P}.convention", f"unknown convention {convention!r} (expected one of {', '.join(CONVENTIONS)}; "
               "a run reads another way with its own convention = \"B0=+X,B90=+Z\", docs/conventions.md)")
    cr_geometry = r.string(t, "cr_geometry", P, default="RC-LB")
    if cr_geometry not in CR_GEOMETRIES:
        r.fail(f"{P}.cr_geometry", f"unknown CR geometry {cr_geometry!r} (expected {' or '.join(CR_GEOMETRIES)})")
    length = r.number(t, "length_mm", P, positive=True)
    accuracy = units.to_internal(r.number(t, "accuracy_um", P, positive=True), "um")
    feed = r.number(t, "feed_mm_per_min", P, required=False, positive=True)

    setups: dict[str, Setup] = {}
    for sid, path, s in r.subtables(t, "setups", P, allowed={"R_B_mm", "Z_T_mm", "X_T_mm"}, what="tool setup"):
        setups[sid] = Setup(sid, r.number(s, "R_B_mm", path, positive=True),
                            r.number(s, "Z_T_mm", path), r.number(s, "X_T_mm", path))
    _distinct_tool_lengths(r, [(f"{P}.setups.{s.id}", s.R_B, s.Z_T) for s in setups.values()])

    mounts: dict[str, Mount] = {}
    for mid, path, m in r.subtables(t, "mounts", P, allowed={"Z_C_mm", "R_C_mm"}, what="W-ball mount"):
        mounts[mid] = Mount(mid, r.number(m, "Z_C_mm", path, nonnegative=True),
                            r.number(m, "R_C_mm", path, nonnegative=True))

    raw_runs = t.get("runs", [])  # absent: a machine with set-ups and mounts but nothing measured or planned yet
    if not isinstance(raw_runs, list) or not all(isinstance(x, dict) for x in raw_runs):
        r.fail(f"{P}.runs", "expected one or more [[ballbar.runs]] tables")
    items = [_run(r, x, f"{P}.runs[{i}]", setups=setups, mounts=mounts, base_dir=base_dir, L_B=length,
                  cr_geometry=cr_geometry) for i, x in enumerate(raw_runs)]
    _distinct_runs(r, items, P)
    runs = [x for x in items if isinstance(x, Run)]
    planned = planned_in_order(r, [(i, x) for i, x in enumerate(items) if isinstance(x, PlannedRun)], P)
    bb = Ballbar(length, accuracy, r.string(t, "instrument", P), feed, setups, mounts, runs, cr_geometry, convention,
                 planned)
    for i, run in enumerate(items):
        try:
            check_run(run, bb) if isinstance(run, Run) else run_matrix(run, bb)
        except ConventionError as err:
            r.fail(f"{P}.runs[{i}].convention" if run.convention else f"{P}.convention", str(err))
    _reading_choice(r, t, items, bb)
    return bb


def _reading_choice(r: TomlReader, t: dict, items: list[Run | PlannedRun], bb: Ballbar) -> None:
    """Check each run's ``alternative_convention`` as its ``convention`` is checked, and that it reads the run
    otherwise; set ``bb.alternative_reason`` (one line, only where some run names an alternative)."""
    P = "ballbar"
    for i, run in enumerate(items):
        if not isinstance(run, Run) or run.alternative_convention is None:
            continue
        key = f"{P}.runs[{i}].alternative_convention"
        other = dataclasses.replace(run, convention=run.alternative_convention)
        try:
            check_run(other, bb)
        except ConventionError as err:
            r.fail(key, str(err))
        if np.allclose(run_matrix(other, bb), run_matrix(run, bb)):
            r.fail(key, f"{run.alternative_convention!r} reads run {run.label} as its reading "
                   f"({run_convention(run, bb)!r}) does: an alternative reads it otherwise")
    reason = r.string(t, "alternative_reason", P).strip()
    if "\n" in reason:
        r.fail(f"{P}.alternative_reason", "expected one line (it is shown beside every number that rests on the choice)")
    if reason and not bb.reading_choices():
        r.fail(f"{P}.alternative_reason", "no run names an alternative_convention: there is no choice of reading to "
               "give a reason for")
    bb.alternative_reason = reason


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


def _distinct_runs(r: TomlReader, runs: list[Run | PlannedRun], path: str) -> None:
    """Two runs of one pattern, setup and mount are refused (``docs/campaign-format.md``, "Duplicate runs"):
    merged they would pass two sessions, perhaps a re-clamped ball, for repeats of one measurement, whose
    repeat sd the likelihood takes as the run's repeatability.  Measured and planned runs alike (the file's
    order, ``runs`` indexing ``[[ballbar.runs]]``)."""
    first: dict[tuple[str, str, str], int] = {}
    for i, run in enumerate(runs):
        j = first.setdefault((run.pattern, run.setup, run.mount), i)
        if j != i:
            if isinstance(run, PlannedRun) or isinstance(runs[j], PlannedRun):
                where = "plan one run with all its repeats (repeats = N)"
                if isinstance(runs[j], Run):
                    where = "a run already measured is not planned again on the same placement"
            else:
                arrays = ('trace_csv = ["a.csv", "b.csv"]' if run.trace_csv or runs[j].trace_csv
                          else f"{COMPONENTS[run.pattern][0]}_um = [..., ...]")
                where = f"put all repeats of one measurement in one run's arrays ({arrays})"
            r.fail(f"{path}.runs[{i}]", f"repeats {path}.runs[{j}] (pattern {run.pattern}, setup {run.setup!r}, "
                   f"mount {run.mount!r}): {where}; if the ball was re-clamped, give it its own [{path}.mounts.<id>]")


def _run(r: TomlReader, t: dict, path: str, *, setups, mounts, base_dir, L_B: float,
         cr_geometry: str) -> Run | PlannedRun:
    r.check_keys(t, {"pattern", "setup", "mount", "convention", "alternative_convention", "planned", *DATA_KEYS,
                     *PLANNED_KEYS}, path)
    planned = t.get("planned", False)
    if not isinstance(planned, bool):
        r.fail(f"{path}.planned", "expected true (a run planned but not yet measured) or false, got "
               f"{kind_of(planned)}")
    if not planned:
        for key in PLANNED_KEYS:
            if key in t:
                r.fail(f"{path}.{key}", "only a planned run (planned = true) has this key; a measured run gives its "
                       "repeats as arrays (ex_um = [..., ...]) or trace_csv")
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
    if planned:
        if "alternative_convention" in t:
            r.fail(f"{path}.alternative_convention", "a planned run has no offsets to read another way; give it once "
                   "the run is measured")
        return _planned_run(r, t, path, pattern=pattern, setup=setup, mount=mount, L_B=L_B)
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
    return Run(pattern, setup, mount, repeats, traces, rms, _convention_of(r, t, path),
               _convention_of(r, t, path, "alternative_convention"))


def _convention_of(r: TomlReader, t: dict, path: str, key: str = "convention") -> str | None:
    convention = r.string(t, key, path, default="") or None
    if convention is not None:
        try:
            check_convention_name(convention)
        except ConventionError as err:
            r.fail(f"{path}.{key}", str(err))
    return convention


def _planned_run(r: TomlReader, t: dict, path: str, *, pattern: str, setup: str, mount: str,
                 L_B: float) -> PlannedRun:
    """A run with ``planned = true``: :func:`.planned_runs.planned_run`, with its reading convention and a bar length
    other than the campaign's."""
    data = [k for k in DATA_KEYS if k in t]
    if data:
        r.fail(f"{path}.planned", f"planned = true but the run has data ({', '.join(data)}): once it is measured, "
               "delete planned and repeats")
    run = planned_run(r, t, path, pattern=pattern, setup=setup, mount=mount)
    length = r.number(t, "length_mm", path, required=False, positive=True)
    run.convention = _convention_of(r, t, path)
    run.length = None if length == L_B else length
    return run

def _probe(r: TomlReader, t: dict, base_dir: Path | None) -> Probe:
    P = "probe"
    r.check_keys(t, {"instrument", "repeatability_um", "c_axis", "b_axis"}, P)
    rep = r.number(t, "repeatability_um", P, required=False, positive=True)
    probe = Probe(r.string(t, "instrument", P), units.to_internal(rep, "um") if rep is not None else None)
    b = r.table(t, "b_axis", P, required=False)
    if b is not None:
        path = f"{P}.b_axis"
        r.check_keys(b, {"X_T_mm", "Z_C_mm", "angles_deg", "styli"}, path)
        angles = r.array(b, "angles_deg", path, (None,))
        if len(np.unique(angles)) < 2:
            r.fail(f"{path}.angles_deg", f"needs at least two different B angles (only differences between indexed "
                   f"positions inform the deviations), got [{', '.join(f'{a:g}' for a in angles)}]")
        bax = BAxisProbe(r.number(b, "X_T_mm", path), angles, Z_C=r.number(b, "Z_C_mm", path, required=False))
        for sid, sp, st in r.subtables(b, "styli", path, what="stylus",
                                       allowed={"R_B_mm", "nominal_mm", "centres_mm", "dprnt", "ball_radius_mm"}):
            centres, cov, files = _readings(r, st, sp, len(angles), base_dir=base_dir)
            bax.styli[sid] = Stylus(sid, r.number(st, "R_B_mm", sp, positive=True),
                                    r.array(st, "nominal_mm", sp, (len(angles), 3), required=False), centres,
                                    ball_radius=r.number(st, "ball_radius_mm", sp, required=False, nonnegative=True,
                                                         default=0.0),
                                    dprnt=files, centre_cov=cov)
        for i, (sa, a) in enumerate(bax.styli.items()):
            for sb, bb in list(bax.styli.items())[i + 1:]:
                if a.R_B == bb.R_B:
                    r.fail(f"{path}.styli.{sb}.R_B_mm", f"equal to styli.{sa}.R_B_mm ({a.R_B:g} mm): "
                           "a second stylus length equal to the first carries no information")
        probe.b_axis = bax
    c = r.table(t, "c_axis", P, required=False)
    if c is not None:
        path = f"{P}.c_axis"
        r.check_keys(c, {"R_C_mm", "Z_C_mm", "axis_xy_mm", "angles_deg", "centres_mm", "dprnt", "stylus", "R_B_mm",
                         "ball_radius_mm", "datum"}, path)
        angles = r.array(c, "angles_deg", path, (None,))
        if len(np.unique(np.mod(angles, 360.0))) < 3:
            r.fail(f"{path}.angles_deg", f"needs at least three different C angles (a circle through the sphere "
                   f"centres), got [{', '.join(f'{a:g}' for a in angles)}]")
        centres, cov, files = _readings(r, c, path, len(angles), base_dir=base_dir)
        stylus = r.string(c, "stylus", path, default="") or None
        R_B = r.number(c, "R_B_mm", path, required=False, positive=True)
        if stylus is not None:
            if probe.b_axis is None or stylus not in probe.b_axis.styli:
                have = ", ".join(probe.b_axis.styli) if probe.b_axis else "none"
                r.fail(f"{path}.stylus", f"no stylus {stylus!r} in [probe.b_axis.styli] (have: {have})")
            if R_B is not None:
                r.fail(f"{path}.R_B_mm", "give either stylus (a stylus of [probe.b_axis.styli]) or R_B_mm, not both")
        datum = r.string(c, "datum", path, default="machine")
        if datum not in ("machine", "first"):
            r.fail(f"{path}.datum", f"unknown datum {datum!r} (expected \"machine\": the readings are machine "
                   "coordinates with the C axis at axis_xy_mm, or \"first\": the reading frame was zeroed on the sphere)")
        probe.c_axis = CAxisProbe(
            r.number(c, "R_C_mm", path, positive=True), r.number(c, "Z_C_mm", path, nonnegative=True),
            r.array(c, "axis_xy_mm", path, (2,)), angles, centres, stylus=stylus, R_B=R_B,
            ball_radius=r.number(c, "ball_radius_mm", path, required=False, nonnegative=True, default=0.0),
            datum=datum, dprnt=files, centre_cov=cov)
    return probe


#: fewest probed points of a sphere fit whose centre covariance the likelihood can use (4 fit it exactly)
MIN_DPRNT_POINTS = 5


def _readings(r: TomlReader, t: dict, path: str, n_angles: int, *, base_dir: Path | None):
    """Sphere centres of a probe run: ``centres_mm`` (r, a, 3), or one DPRNT file per angle, each fitted
    (one repeat, with the centre covariance of the fit).  Returns ``(centres, cov or None, files or None)``."""
    has_c, has_d = "centres_mm" in t, "dprnt" in t
    if has_c == has_d:
        r.fail(path, "no readings: give centres_mm (repeats x angles x 3) or dprnt (one DPRNT file per angle)"
               if not has_c else "give either centres_mm or dprnt, not both")
    if has_c:
        return r.array(t, "centres_mm", path, (None, n_angles, 3)), None, None
    files = t["dprnt"]
    key = f"{path}.dprnt"
    if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
        r.fail(key, f"expected an array of file names, got {kind_of(files)}")
    if len(files) != n_angles:
        r.fail(key, f"{len(files)} files for {n_angles} angles: give one DPRNT file per indexed position")
    centres, cov = np.empty((1, n_angles, 3)), np.empty((1, n_angles, 3, 3))
    for i, name in enumerate(files):
        fpath = (base_dir / name) if base_dir is not None else data_path(name)
        try:
            pts = read_dprnt(fpath).xyz
            if len(pts) < MIN_DPRNT_POINTS:
                raise MtmcalError(f"{len(pts)} probed points; a sphere fit with a covariance needs at least "
                                  f"{MIN_DPRNT_POINTS}")
            fit = fit_sphere(pts)
        except MtmcalError as err:
            r.fail(f"{key}[{i}]", str(err) if isinstance(err, InputError) else f"{name}: {err}")
        centres[0, i], cov[0, i] = fit.centre, fit.centre_cov
    return centres, cov, list(files)


def _reported(r: TomlReader, t: dict, text: str) -> dict[str, dict[str, ReportedValue]]:
    out: dict[str, dict[str, ReportedValue]] = {}
    for method, vals in t.items():
        path = f"reported.{method}"
        if not isinstance(vals, dict):
            r.fail(path, f"expected a table, got {kind_of(vals)}")
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


def _prior_bounds(r: TomlReader, v: float, key: str, *, unit: str, sd: bool) -> None:
    """A number of a prior (″ or µm) within ±PRIOR_LIMIT; an sd also at least PRIOR_RESOLUTION."""
    sym = ("" if unit == "arcsec" else " ") + units.SYMBOL[unit]
    limit, shown = PRIOR_LIMIT[unit]
    if abs(v) > limit:
        r.fail(key, f"{v:g}{sym} is beyond ±{limit:g}{sym} ({shown}): no geometric deviation, offset or model "
               "discrepancy of a machine tool is that large")
    if sd and v < PRIOR_RESOLUTION:
        r.fail(key, f"{v:g}{sym} is below {PRIOR_RESOLUTION:g}{sym}: a prior that narrow fixes the parameter "
               "below the models' floating-point resolution")


def _priors(r: TomlReader, t: dict, deviations: dict | None = None) -> dict[str, dict]:
    known = {**{k: q.unit for k, q in (DEVIATIONS if deviations is None else deviations).items()},
             **{k: q.unit for k, q in {**SETUP_NUISANCE, **MOUNT_NUISANCE, **PROBE_NUISANCE}.items()},
             **{scale: "um" for scale in SCALES}}
    out = {}
    for name, spec in t.items():
        path = f"priors.{name}"
        if name not in known:
            r.fail(path, "unknown parameter (expected a deviation name, one of xT yT zT dRB xW yW zW, "
                   f"a probe term ({' '.join(PROBE_NUISANCE)}) or a discrepancy scale ({' '.join(SCALES)}))")
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
            _prior_bounds(r, v, f"{path}.{p}_{unit}", unit=unit, sd=(p == "sd"))
            parsed[p] = units.to_internal(v, unit)
        if dist == "uniform" and parsed["high"] <= parsed["low"]:
            r.fail(f"{path}.high_{unit}", "must be greater than low")
        if dist == "uniform" and spec[f"high_{unit}"] - spec[f"low_{unit}"] < PRIOR_RESOLUTION:
            r.fail(f"{path}.high_{unit}", f"must exceed low by at least {PRIOR_RESOLUTION:g} "
                   f"{units.SYMBOL[unit]}: a narrower prior fixes the parameter below the models' resolution")
        if name in SCALES:  # a standard deviation: the sampler only visits a scale > 0
            for p in ("low", "mean"):
                if parsed.get(p, 0.0) < 0:
                    r.fail(f"{path}.{p}_{unit}", f"must not be negative for {name} (a standard deviation), "
                           f"got {units.from_internal(parsed[p], unit):g}")
        out[name] = parsed
    return out


def _design(r: TomlReader, t: dict, known: dict) -> DesignGoal:
    """``[design]``: ``targets`` (quantity -> standard uncertainty, ″ or µm), ``contraction`` (0 < c < 1),
    ``budget_min`` (> 0) and ``times`` (machine-time overrides, minutes; their names are the planner's)."""
    P = "design"
    r.check_keys(t, {"targets", "contraction", "budget_min", "times"}, P)
    goal = DesignGoal()
    for key in r.table(t, "targets", P, required=False) or {}:
        full = f"{P}.targets.{key}"
        name, unit = units.split_unit_key(key)
        q = known.get(name)
        if q is None or unit not in (None, q.unit):
            r.fail(full, "unknown quantity: expected a canonical name (" + ", ".join(known) + "), with or "
                   "without its unit (alpha_BT_arcsec for an angle, dy_CZ_um for a length)")
        if name in goal.targets:
            r.fail(full, f"a second target for {name}: give it once")
        sd = r.number(t["targets"], key, f"{P}.targets", positive=True)
        limit, shown = PRIOR_LIMIT[q.unit]
        if sd > limit:
            r.fail(full, f"{sd:g} {units.SYMBOL[q.unit]} is beyond {limit:g} {units.SYMBOL[q.unit]} ({shown}): not a "
                   "standard uncertainty a calibration aims for")
        goal.targets[name] = sd
    goal.contraction = r.number(t, "contraction", P, required=False)
    if goal.contraction is not None and not 0.0 < goal.contraction < 1.0:
        r.fail(f"{P}.contraction", f"{goal.contraction:g} is not a contraction: the share by which σ_model's "
               "uncertainty shrinks is between 0 and 1 (exclusive), e.g. 0.5")
    goal.budget_min = r.number(t, "budget_min", P, required=False, positive=True)
    for key in r.table(t, "times", P, required=False) or {}:
        goal.times[key] = r.number(t["times"], key, f"{P}.times", nonnegative=True)
    return goal


def parse_truth(r: TomlReader, t: dict, path: str, ballbar: Ballbar, *, probe: Probe | None = None,
                machine: Machine | None = None) -> Truth:
    """Parse truth tables (``deviations``, ``setups.<id>``, ``mounts.<id>``, ``probe.<owner>``) located at ``path``;
    a described ``machine``'s deviations by their ISO symbols (its thesis names on the thesis machine)."""
    r.check_keys(t, {"deviations", "setups", "mounts", "probe"}, path)
    truth = Truth()
    known = deviation_quantities(machine) if machine is not None else DEVIATIONS
    dev = r.table(t, "deviations", path, required=False) or {}
    for key in dev:
        name, unit = units.split_unit_key(key)
        q = known.get(name)
        if q is None or unit != q.unit:
            r.fail(f"{path}.deviations.{key}", "unknown deviation: expected <name>_arcsec or <name>_um "
                   f"with one of {', '.join(known)}")
        truth.deviations[name] = units.to_internal(r.number(dev, key, f"{path}.deviations"), unit)
    owners_of = provided(machine, "probe_owners", engine_probe_owners) if machine is not None else thesis_probe_owners
    probe_owners = owners_of(machine, probe) if probe is not None else set()
    for group, table, owners in (("setups", SETUP_NUISANCE, ballbar.setups),
                                 ("mounts", MOUNT_NUISANCE, ballbar.mounts),
                                 ("probe", PROBE_NUISANCE, probe_owners)):
        for oid, vals in (r.table(t, group, path, required=False) or {}).items():
            op = f"{path}.{group}.{oid}"
            if oid not in owners:
                where = "[probe] (its styli, c_axis, b_axis)" if group == "probe" else f"[ballbar.{group}]"
                r.fail(op, f"no such {group.rstrip('s')} in {where} (have: {', '.join(owners) or 'none'})")
            if not isinstance(vals, dict):
                r.fail(op, f"expected a table, got {kind_of(vals)}")
            r.check_keys(vals, {f"{k}_um" for k in table}, op)
            getattr(truth, group)[oid] = {k[:-3]: units.to_internal(r.number(vals, k, op), "um") for k in vals}
    return truth




#: the thesis machine's configuration (a [machine] table in the thesis format describes it)
THESIS_CONFIGURATION = "w-C'bZYXB(C1)-t"


def load_truth(path, campaign: Campaign) -> Truth:
    """Read a TRUTH.toml: ``[deviations]``, ``[setups.<id>]``, ``[mounts.<id>]``, ``[probe.<owner>]`` at top level,
    or the same under ``[truth]`` as a campaign writes them (``[truth.deviations]``, docs/campaign-format.md; a
    campaign file with its ``[truth]`` works too).  Both spellings in one file is an error naming ``truth``."""
    text = read_user_text(path, "truth file")
    doc = parse_toml(text, str(path), "[deviations], [setups.<id>], [mounts.<id>] tables")
    r = TomlReader(str(path))
    if "truth" in doc:
        if TRUTH_TABLES & set(doc):
            r.fail("truth", f"both [truth.…] and top-level [{'], ['.join(sorted(TRUTH_TABLES & set(doc)))}]: write "
                   "the truth one way")
        return parse_truth(r, r.table(doc, "truth", ""), "truth", campaign.ballbar, probe=campaign.probe,
                           machine=campaign.machine)
    return parse_truth(r, doc, "", campaign.ballbar, probe=campaign.probe, machine=campaign.machine)


#: the tables of a truth
TRUTH_TABLES = {"deviations", "setups", "mounts", "probe"}


def engine_probe_owners(machine: Machine, probe: Probe) -> set[str]:
    """The owners of a described machine's probe nuisance terms (its styli and spheres)."""
    return {o for o, _ in probe_terms(machine.description, probe)}


def thesis_probe_owners(machine: Machine | None, probe: Probe) -> set[str]:
    """The owners of the probe nuisance terms in the thesis' campaign format (its styli, ``c_axis``, ``b_axis``)."""
    return {o for o, _ in probe.nuisance_terms()}
