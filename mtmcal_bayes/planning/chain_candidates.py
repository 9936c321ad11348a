"""A candidate run's arc and held axes, and the user's candidates of a machine from its description (SPEC §19):
``--candidates`` files with ``position_mm``, ``arc_deg`` and ``hold_deg`` (the catalogue is :mod:`.catalogue`'s)."""

from __future__ import annotations

import numpy as np

from ..campaign import Mount, Run, Setup
from ..machines.patterns import axis_of, components, default_arc_deg, patterns_of
from .candidates import Candidate


def arc_of(candidate: Candidate, desc) -> np.ndarray:
    """The swivelled axis' angles of ``candidate`` (k,), degrees."""
    if candidate.arc_deg is None:
        return default_arc_deg(axis_of(desc, candidate.pattern))
    lo, hi, step = candidate.arc_deg
    return np.arange(lo, hi + 1e-9, step)


def arc_spec(arc_deg) -> tuple[float, float, float] | None:
    """A run's angles (k,) degrees as a candidate's ``(start, end, step)``; None for none (the axis' default)."""
    if arc_deg is None or len(arc_deg) < 2:
        return None
    return float(arc_deg[0]), float(arc_deg[-1]), float(arc_deg[1] - arc_deg[0])


def run_of(candidate: Candidate, desc) -> Run:
    """The candidate as a campaign run (zero readings, ``repeats`` each: the rows do not depend on them)."""
    return Run(candidate.pattern, candidate.setup.id, candidate.mount.id,
               {c: np.zeros(candidate.repeats) for c in components(desc, candidate.pattern)},
               arc_deg=arc_of(candidate, desc), hold_deg=dict(candidate.hold_deg) or None)


#: the keys of a candidate of a machine from its description (``plan``/``design`` ``--candidates``)
CHAIN_KEYS = {"name", "pattern", "setup", "mount", "R_B_mm", "position_mm", "arc_deg", "hold_deg", "length_mm",
              "repeats"}


def read_chain_candidates(path, campaign) -> list[Candidate]:
    """Candidates of a machine from its description, by the user, in a TOML file of ``[[candidate]]`` tables: a
    ``pattern`` ``<axis><R|T|A|X|Y|Z>`` of the machine; ``setup = "<id>"`` or ``R_B_mm`` of a new tool length;
    ``mount = "<id>"`` or ``position_mm = [x, y, z]`` of a new W-ball placement; optional ``arc_deg = [start, end,
    step]`` (default the axis' grid), ``hold_deg = {letter = degrees}`` (the other rotary axes), ``length_mm``,
    ``repeats`` and ``name``.  Its travels are checked with the catalogue's (:func:`.catalogue.feasibility_check`)."""
    from .candidates import _existing, _length, candidate_run, candidate_tables

    r, items = candidate_tables(path)
    desc = campaign.machine.description
    bb = campaign.ballbar
    pats = patterns_of(desc)
    out = []
    for i, t in enumerate(items):
        where = f"candidate[{i}]"
        r.check_keys(t, CHAIN_KEYS, where)
        pattern = r.string(t, "pattern", where, required=True)
        if pattern not in pats:
            r.fail(f"{where}.pattern", f"unknown pattern {pattern!r} for this machine (expected one of "
                   f"{' '.join(pats)})")
        setup = _existing(r, t, "setup", path=where, known=bb.setups, geometry=("R_B_mm",)) or Setup(
            f"user{i}", _length(r, t, "R_B_mm", where, positive=True), 0.0, 0.0)
        mount = _existing(r, t, "mount", path=where, known=bb.mounts, geometry=("position_mm",)) or Mount(
            f"user{i}", 0.0, 0.0, position=_vector(r, t, "position_mm", where))
        length, repeats, name = candidate_run(r, t, where, campaign, pattern=pattern, setup=setup, mount=mount)
        out.append(Candidate(name, "user", pattern, setup, mount, length, repeats,
                             extension=setup.R_B - campaign.primary_setup().R_B, arc_deg=_arc(r, t, where),
                             hold_deg=_held(r, t, where, desc=desc, pattern=pattern)))
    return out


def _vector(r, t: dict, key: str, where: str) -> np.ndarray:
    v = t.get(key)
    if not (isinstance(v, list) and len(v) == 3 and all(isinstance(x, (int, float)) and np.isfinite(x) for x in v)):
        r.fail(f"{where}.{key}", "expected [x, y, z] in mm (the W ball's centre at the home pose), or mount = \"<id>\"")
    return np.asarray(v, float)


def _arc(r, t: dict, where: str) -> tuple[float, float, float] | None:
    if "arc_deg" not in t:
        return None
    v = t["arc_deg"]
    if not (isinstance(v, list) and len(v) == 3 and all(isinstance(x, (int, float)) for x in v)
            and v[2] > 0 and v[1] > v[0]):
        r.fail(f"{where}.arc_deg", "expected [start, end, step] in degrees, end after start, a positive step")
    return float(v[0]), float(v[1]), float(v[2])


def _held(r, t: dict, where: str, *, desc, pattern: str) -> tuple[tuple[str, float], ...]:
    held = t.get("hold_deg", {})
    if not isinstance(held, dict):
        r.fail(f"{where}.hold_deg", "expected a table {letter = degrees} of the other rotary axes")
    others = [a.letter for a in desc.rotary_axes if a.letter != pattern[0]]
    for a in held:
        if a not in others:
            r.fail(f"{where}.hold_deg.{a}", f"not another rotary axis of the machine (its others: "
                   f"{', '.join(others) or 'none'})")
    return tuple((a, float(r.number(held, a, f"{where}.hold_deg"))) for a in held)
