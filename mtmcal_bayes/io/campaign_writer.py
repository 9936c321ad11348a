"""Writing campaigns as TOML (``mtmcal-campaign/1``): file units, traces relative to the file, atomically.

One writer for every machine, the inverse of the one reader (:mod:`.campaign_reader`): the format line, date and
temperature, ``[ballbar]`` (:mod:`.ballbar_writer`), the probe's instrument and repeatability, ``[rtest]``
(:mod:`.rtest_section`), ``[reported]``,
``[priors]``, ``[tolerances]``, ``[truth]`` and ``[design]`` are the engine's; the machine contributes what its
campaign format has of its own — its keys of ``[ballbar]`` (its ``ballbar_keys``) and its probe's sections
(``probe_document``, for the runs read from them) — and the engine writes every other probe run as
``[[probe.runs]]``.  ``[machine]`` is the engine's on every machine (:mod:`.description_writer`: a built-in type
named, any other description written out).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

from .. import units
from ..campaign import Campaign, Probe
from ..machines.plugins import provided
from ..parameters import quantity_unit
from .ballbar_section import EngineKeys
from .ballbar_writer import ballbar_to_dict, relative_path
from .campaign_reader import FORMAT, deviation_quantities
from .description_writer import machine_table
from .design_table import design_to_dict
from .rtest_section import rtest_document
from .textfiles import write_text_atomic
from .tomlio import Fixed, dumps
from .truth_table import truth_to_dict


def campaign_to_dict(c: Campaign, save_dir: Path | None = None) -> dict:
    """The TOML document of a campaign (file units), as nested dicts.

    Trace and DPRNT files are written relative to ``save_dir`` (absolute when ``None``).
    """
    doc: dict = {"format": FORMAT}
    if c.date is not None:
        doc["date"] = c.date
    if c.temperature_C is not None:
        doc["temperature_C"] = c.temperature_C
    m = c.machine
    doc["machine"] = machine_table(m)
    ballbar = ballbar_to_dict(c, provided(m, "ballbar_keys", EngineKeys), save_dir)
    if ballbar is not None:
        doc["ballbar"] = ballbar
    probe = _probe(c, lambda name: relative_path(c, name, save_dir)) if c.probe is not None else {}
    if probe:  # a probe that states nothing (no instrument, repeatability, stylus or run) is not written
        doc["probe"] = probe
    if c.rtest is not None:
        doc["rtest"] = rtest_document(c.rtest)
    quantities = provided(m, "quantity_table") or deviation_quantities(m)  # the names the reader takes

    def unit(name: str) -> str:  # a quantity's, a nuisance term's or a discrepancy scale's
        return quantities[name].unit if name in quantities else quantity_unit(name)

    if c.reported:
        doc["reported"] = {method: {f"{n}_{v.unit}": Fixed(units.from_internal(v.value, v.unit), v.decimals)
                                    for n, v in values.items()} for method, values in c.reported.items()}
    if c.priors:
        doc["priors"] = {name: {"dist": spec["dist"], **{f"{k}_{unit(name)}": units.from_internal(v, unit(name))
                                                        for k, v in spec.items() if k != "dist"}}
                         for name, spec in c.priors.items()}
    if c.tolerances:
        doc["tolerances"] = {f"{name}_{unit(name)}": _tolerance(t, unit(name)) for name, t in c.tolerances.items()}
    if c.truth is not None:
        doc["truth"] = truth_to_dict(c.truth)
    if c.design is not None:
        doc["design"] = design_to_dict(c.design, quantities)
    return doc


def _probe(c: Campaign, path_of: Callable[[str], str]) -> dict:
    """``[probe]``: its instrument and repeatability, the runs read from a plug-in's sections in them (its
    ``probe_document``), the others as ``[probe.styli]`` and ``[[probe.runs]]``; ``path_of`` writes a file's name as
    seen from the saved file."""
    p = c.probe
    d: dict = {"instrument": p.instrument} if p.instrument else {}
    if p.repeatability is not None:
        d["repeatability_um"] = units.from_internal(p.repeatability, "um")
    d.update(provided(c.machine, "probe_document", lambda probe, path_of: {})(p, path_of))
    d.update(probe_runs(p, path_of))
    return d


def probe_runs(p: Probe, path_of: Callable[[str], str]) -> dict:
    """The engine's keys of ``[probe]`` (:mod:`.measurement_sections`): ``[probe.styli.<id>] length_mm`` and
    ``[[probe.runs]]`` with their stylus, sphere, angles and centres or DPRNT files (``path_of``: a file's name as seen
    from the saved campaign), for the runs read from no plug-in's section and the styli none of those use (none
    where there are neither)."""
    theirs = [r for r in p.runs if r.section is not None]
    used = {r.stylus for r in theirs}
    styli = {sid: {"length_mm": float(length), **({"ball_radius_mm": float(p.ball_radii[sid])}
                                                  if p.ball_radii.get(sid) else {})}
             for sid, length in p.styli.items() if sid not in used}
    runs = [{"id": r.id, "stylus": r.stylus, "sphere_mm": [float(x) for x in r.sphere],
             "angles_deg": {k: [float(x) for x in units.from_internal(v, "deg")] for k, v in r.angles.items()},
             **({"dprnt": [path_of(f) for f in r.dprnt]} if r.dprnt else {"centres_mm": r.centres})}
            for r in p.runs if r.section is None]
    return {**({"styli": styli} if styli else {}), **({"runs": runs} if runs else {})}


def _tolerance(t, unit: str):
    """A tolerance as written: ``± limit`` where symmetric, else ``{low, high}`` (the ends it has)."""
    ends = {k: units.from_internal(v, unit) for k, v in (("low", t.low), ("high", t.high)) if v is not None}
    return ends["high"] if t.low is not None and t.high is not None and t.low == -t.high else ends


def save_campaign(campaign: Campaign, path: str | os.PathLike, header: str | None = None) -> None:
    """Write ``campaign`` as TOML to ``path`` (atomically); ``header`` becomes a leading comment."""
    text = dumps(campaign_to_dict(campaign, Path(path).resolve().parent))
    if header:
        text = "".join(f"# {line}\n" for line in header.splitlines()) + "\n" + text
    write_text_atomic(path, text)
