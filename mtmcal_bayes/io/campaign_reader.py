"""Reading campaign TOML files (``mtmcal-campaign/1``) with validation, and truth files.

A campaign file (see ``docs/campaign-format.md``) describes one calibration:
the machine, the ball-bar setups, mounts and runs, touch-probe data, published
results, optional priors and, for synthetic campaigns, the truth.
:func:`load_campaign` reads and validates it into the dataclasses of
:mod:`mtmcal_bayes.campaign` (internal units, mm and rad); every problem is an
:class:`~mtmcal_bayes.errors.InputError` naming the file and the key.
"""

from __future__ import annotations

import datetime
import os
from pathlib import Path

from .. import units
from ..campaign import Ballbar, Campaign, DesignGoal, Machine, Probe, Truth
from ..datasets import builtin_campaign_text
from ..parameters import (
    DEVIATIONS,
    DISCREPANCY_SCALES,
    MOUNT_NUISANCE,
    PROBE_NUISANCE,
    RTEST_NUISANCE,
    SETUP_NUISANCE,
)
from ..machines.deviations import quantities as deviation_table
from ..machines.plugins import provided
from .measurement_sections import measurement_sections
from .machine_reader import (BUILTIN_TYPES, DESCRIPTION_KEYS, THESIS_TYPE, builtin_description, parse_description,
                             referenced_description)
from .textfiles import read_user_text
from .tolerances import machine_names, parse_tolerances
from .toml_reader import TomlReader, kind_of, parse_toml

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
    r.check_keys(doc, {"format", "machine", "ballbar", "probe", "rtest", "reported", "priors", "truth", "tolerances", "date",
                       "temperature_C", "design"}, "")
    fmt = r.string(doc, "format", "", required=True)
    if fmt != FORMAT:
        r.fail("format", f"unknown format {fmt!r} (this version reads {FORMAT!r})")

    machine = _machine(r, doc.get("machine"), base_dir)
    ballbar, probe, rtest = measurement_sections(r, doc, machine, base_dir)
    deviations = deviation_quantities(machine)
    reported = {}
    if "reported" in doc:  # a plug-in's published values (the thesis': Tables 4.5 and 5.3), read by the plug-in
        read_reported = provided(machine, "read_reported")
        if read_reported is None:
            r.fail("reported", "not read for this machine: it has no reported quantities (a plug-in's published "
                   "values, docs/machines.md)")
        reported = read_reported(r, r.table(doc, "reported", ""), text)
    priors = _priors(r, r.table(doc, "priors", "", required=False) or {}, deviations)
    truth_t = r.table(doc, "truth", "", required=False)
    truth = parse_truth(r, truth_t, "truth", ballbar, probe=probe, machine=machine, rtest=rtest) \
        if truth_t is not None else None
    tolerances = parse_tolerances(r, r.table(doc, "tolerances", "", required=False) or {},
                                  names=machine_names(machine))
    temperature = r.number(doc, "temperature_C", "", required=False)
    if temperature is not None and not -50.0 <= temperature <= 100.0:
        r.fail("temperature_C", f"{temperature:g} °C is not a workshop temperature (−50 to 100 °C)")
    design_t = r.table(doc, "design", "", required=False)
    design = _design(r, design_t, provided(machine, "quantity_table", deviations)) if design_t is not None else None
    return Campaign(machine, ballbar, probe, reported, priors, truth, source, base_dir, tolerances,
                    _date(r, doc), temperature, design, rtest)


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
        name = r.string(t, "name", "machine") if "name" in t else desc.name  # an empty name given stays empty
        return Machine(name, desc.configuration, travel, serial, mtype, desc)
    if set(t) & (DESCRIPTION_KEYS - {"name", "configuration"}):
        desc = parse_description(t, r.source, "machine", extra_keys=frozenset(legacy))
        return Machine(desc.name, desc.configuration, travel, serial, mtype, desc)
    configuration = r.string(t, "configuration", "machine")
    if configuration and configuration.replace(" ", "") != THESIS_CONFIGURATION:
        r.fail("machine.configuration", f"{configuration!r} is not the thesis machine's ({THESIS_CONFIGURATION}) and "
               "nothing describes it: add [machine.axes.<letter>] and [machine.spindle] (docs/machines.md) or name a "
               f"built-in type with description = \"...\" ({', '.join(BUILTIN_TYPES)})")
    # a campaign in the thesis' first format is of the thesis machine: its built-in description and plug-in, as a
    # campaign naming description = "integrex-i200" (what the writer writes)
    desc = builtin_description(THESIS_TYPE)
    return Machine(r.string(t, "name", "machine"), desc.configuration, travel, serial, mtype, desc)


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
             **{k: q.unit for k, q in {**SETUP_NUISANCE, **MOUNT_NUISANCE, **PROBE_NUISANCE,
                                       **RTEST_NUISANCE}.items()},
             **{scale: "um" for scale in SCALES}}
    out = {}
    for name, spec in t.items():
        path = f"priors.{name}"
        if name not in known:
            r.fail(path, "unknown parameter (expected a deviation name, one of xT yT zT dRB xW yW zW, "
                   f"a probe term ({' '.join(PROBE_NUISANCE)}), an R-test term ({' '.join(RTEST_NUISANCE)}) or a discrepancy scale ({' '.join(SCALES)}))")
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
    ``budget_min`` (> 0), ``times`` (machine-time overrides, minutes; their names are the planner's) and
    ``to_fill_in`` (the designed probe and R-test runs: the id of each one's table -> its name in the design)."""
    P = "design"
    r.check_keys(t, {"targets", "contraction", "budget_min", "times", "to_fill_in"}, P)
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
    for key in r.table(t, "to_fill_in", P, required=False) or {}:
        goal.to_fill_in[key] = r.string(t["to_fill_in"], key, f"{P}.to_fill_in")
    return goal


def parse_truth(r: TomlReader, t: dict, path: str, ballbar: Ballbar, *, probe: Probe | None = None,
                machine: Machine | None = None, rtest=None) -> Truth:
    """Parse truth tables (``deviations``, ``setups.<id>``, ``mounts.<id>``, ``probe.<owner>``, ``rtest.<owner>``)
    located at ``path``; a described ``machine``'s deviations by their ISO symbols (its thesis names on the thesis
    machine)."""
    r.check_keys(t, set(TRUTH_TABLES), path)
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
    probe_owners = {o for o, _ in probe.nuisance_terms(machine.description if machine is not None else None)} \
        if probe is not None else set()
    rtest_owners = {o for o, _ in rtest.nuisance_terms(machine.description)} if rtest is not None else set()
    for group, table, owners in (("setups", SETUP_NUISANCE, ballbar.setups),
                                 ("mounts", MOUNT_NUISANCE, ballbar.mounts),
                                 ("probe", PROBE_NUISANCE, probe_owners),
                                 ("rtest", RTEST_NUISANCE, rtest_owners)):
        for oid, vals in (r.table(t, group, path, required=False) or {}).items():
            op = f"{path}.{group}.{oid}"
            if oid not in owners:
                where = {"probe": "[probe] (its styli and runs)", "rtest": "[rtest] (its runs, placements and "
                         "nests)"}.get(group, f"[ballbar.{group}]")
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
                           machine=campaign.machine, rtest=campaign.rtest)
    return parse_truth(r, doc, "", campaign.ballbar, probe=campaign.probe, machine=campaign.machine,
                       rtest=campaign.rtest)


#: the tables of a truth
TRUTH_TABLES = {"deviations", "setups", "mounts", "probe", "rtest"}


