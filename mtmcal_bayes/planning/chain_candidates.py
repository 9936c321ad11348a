"""Candidate ball-bar runs of a described machine, generated from its description (SPEC §19, docs/design.md).

The catalogue of :func:`described_catalogue`, for the campaign's primary set-up ``T`` and every mount ``W`` (the
other placements below from the first mount):

* every pattern ``<K><d>`` of every rotary axis K (:func:`~mtmcal_bayes.machines.patterns.patterns_of`) over K's
  default arc (a turn by 5°, or 90° by 1° for a tilting axis), the other rotary axes at 0;
* the same with the other rotary axes **held** at :data:`HOLD_DEG` (the first of them within the axis' travel):
  the pattern measured in another pose of the axes above and below K;
* tool lengths ``R_B + e`` for ``e`` in :data:`EXTENSIONS_MM` (a new set-up with its own T-ball offsets) and the
  campaign's unmeasured set-ups;
* the W ball at other **placements** (:data:`PLACEMENTS_MM` added to W's position: its own W-ball offsets);
* bar lengths :data:`OTHER_L_B_MM` (for ``plan``; a design keeps the campaign's bar) and more repeats of the
  measured runs.

Every candidate is checked against the described travels (:func:`described_feasibility_check`): the arc and the
held positions against each rotary axis' travel, every linear command of every point against each linear axis'
travel.  A pattern whose bar has no direction (the ball on the swivelled axis' line) is no measurement and is left
out.
"""

from __future__ import annotations

import numpy as np

from ..campaign import Mount, Run, Setup
from ..machines.patterns import axis_of, components, default_arc_deg, pattern_commands, patterns_of
from .candidates import DEFAULT_REPEATS, Candidate

#: tool-length extensions of the catalogue, mm
EXTENSIONS_MM = (50.0, 100.0, 150.0)
#: held positions tried for the other rotary axes, degrees (the first within the axis' travel is taken)
HOLD_DEG = (90.0, -90.0, 45.0, -45.0, 30.0, -30.0)
#: other W-ball placements of the catalogue: offsets from the first mount's position, mm
PLACEMENTS_MM = ((50.0, 0.0, 0.0), (0.0, 50.0, 0.0), (0.0, 0.0, 100.0))
#: other bar lengths of the catalogue (``plan`` only), mm
OTHER_L_B_MM = (150.0,)


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


def _hold_for(desc, letter: str) -> tuple[tuple[str, float], ...] | None:
    """The other rotary axes of a pattern of axis ``letter`` held at the first of :data:`HOLD_DEG` each allows;
    None when no other rotary axis has such a position."""
    held = []
    for ax in desc.rotary_axes:
        if ax.letter == letter:
            continue
        lo, hi = (-np.inf, np.inf) if ax.travel is None else np.rad2deg(ax.travel)
        pick = next((h for h in HOLD_DEG if lo - 1e-9 <= h <= hi + 1e-9), None)
        if pick is not None:
            held.append((ax.letter, pick))
    return tuple(held) or None


def _label(pattern: str, setup: Setup, mount: Mount, *, hold=(), length: float | None = None) -> str:
    where = f"{pattern} @ {setup.id}/{mount.id}"
    if hold:
        where += ", " + ", ".join(f"{a} held at {v:g}°" for a, v in hold)
    if length is not None:
        where += f", L_B {length:g} mm"
    return where


def described_catalogue(campaign) -> list[Candidate]:
    """The candidate runs of a described machine's campaign (module docstring), feasible or not."""
    desc = campaign.machine.description
    bb = campaign.ballbar
    base = campaign.primary_setup()
    mount = next(iter(bb.mounts.values()))
    L = bb.length
    pats = patterns_of(desc)
    out: list[Candidate] = []

    def add(name, kind, pattern, setup, *, m, length=L, hold=(), repeat_of=None, arc=None):
        out.append(Candidate(name, kind, pattern, setup, m, length, DEFAULT_REPEATS, repeat_of,
                             setup.R_B - base.R_B, arc, tuple(hold or ())))

    measured = {(r.pattern, r.setup, r.mount, tuple(sorted((r.hold_deg or {}).items()))) for r in bb.runs}
    for w in bb.mounts.values():  # every mount of the campaign: each W-ball placement its runs may use
        for p in pats:
            if (p, base.id, w.id, ()) not in measured:
                add(_label(p, base, w), "other pattern", p, base, m=w)
            hold = _hold_for(desc, p[0])
            if hold and (p, base.id, w.id, tuple(sorted(hold))) not in measured:
                add(_label(p, base, w, hold=hold), "held axes", p, base, m=w, hold=hold)
    for w in bb.mounts.values():
        for e in EXTENSIONS_MM:
            s = Setup(f"{base.id}+{e:g}", base.R_B + e, 0.0, 0.0)
            for p in pats:
                add(f"{p} @ R_B+{e:g} mm" + ("" if w is mount else f", mount {w.id}"), "tool length", p, s, m=w)
        for s in bb.setups.values():
            if s.id != base.id:
                for p in pats:
                    if (p, s.id, w.id, ()) not in measured:
                        add(_label(p, s, w) + " (existing setup)", "existing setup", p, s, m=w)
    for k, off in enumerate(PLACEMENTS_MM):
        m = Mount(f"{mount.id}@{k + 1}", 0.0, 0.0, position=np.asarray(mount.position, float) + off)
        shift = ", ".join(f"{a}{v:+g}" for a, v in zip("XYZ", off) if v)
        for p in pats:
            add(f"{p} @ {base.id}, W ball {shift} mm", "other placement", p, base, m=m)
    for i, run in enumerate(bb.runs):
        add(f"repeat {run.label} (+{DEFAULT_REPEATS})", "repeats", run.pattern, bb.setups[run.setup],
            m=bb.mounts[run.mount], hold=tuple((run.hold_deg or {}).items()), repeat_of=i,
            arc=arc_spec(run.arc_deg))
    for L_B in OTHER_L_B_MM:
        if L_B != L:
            for p in pats:
                add(_label(p, base, mount, length=L_B), "bar length", p, base, m=mount, length=L_B)
    return out


def described_feasibility_check(campaign):
    """``check(candidate) -> (feasible, why)`` against the described travels (module docstring)."""
    desc = campaign.machine.description

    def check(c: Candidate) -> tuple[bool, str]:
        try:
            cmd = pattern_commands(desc, c.pattern, length=c.setup.R_B, ball=c.mount.position, bar=c.length,
                                   arc_deg=arc_of(c, desc), hold_deg=dict(c.hold_deg) or None)
        except ValueError as err:
            return False, str(err)
        return travel_problems(desc, cmd.q)

    return check


def travel_problems(desc, q: dict) -> tuple[bool, str]:
    """Whether commands ``q`` {letter: (k,) mm or rad} stay within every described travel, and why not."""
    over = []
    for letter, v in q.items():
        ax = desc.axes.get(letter)
        if ax is None or ax.travel is None:
            continue
        lo, hi = ax.travel
        v = np.asarray(v, float)
        if v.min() < lo - 1e-9 or v.max() > hi + 1e-9:
            if ax.rotary:
                over.append(f"{letter} {np.rad2deg(v.min()):.0f}…{np.rad2deg(v.max()):.0f}° beyond its travel "
                            f"[{np.rad2deg(lo):g}, {np.rad2deg(hi):g}]°")
            else:
                over.append(f"{letter} {v.min():.0f}…{v.max():.0f} mm beyond its travel [{lo:g}, {hi:g}] mm")
    return (not over), ("; ".join(over) if over else "within the axis travels")


__all__ = ["arc_spec", "described_catalogue", "sweep_candidates", "described_feasibility_check", "run_of", "arc_of", "travel_problems",
           "EXTENSIONS_MM", "HOLD_DEG", "PLACEMENTS_MM"]


def sweep_candidates(campaign, pattern: str, extensions) -> list[Candidate]:
    """``pattern`` at the primary set-up plus each extension (mm), at the first mount: the tool-length sweep."""
    base = campaign.primary_setup()
    mount = next(iter(campaign.ballbar.mounts.values()))
    return [Candidate(f"{pattern} @ R_B+{e:g} mm", "sweep", pattern, Setup(f"{base.id}+{e:g}", base.R_B + e, 0.0, 0.0),
                      mount, campaign.ballbar.length, extension=float(e)) for e in extensions]


#: the keys of a candidate of a machine from its description (``plan``/``design`` ``--candidates``)
CHAIN_KEYS = {"name", "pattern", "setup", "mount", "R_B_mm", "position_mm", "arc_deg", "hold_deg", "length_mm",
              "repeats"}


def read_chain_candidates(path, campaign) -> list[Candidate]:
    """Candidates of a machine from its description, by the user, in a TOML file of ``[[candidate]]`` tables: a
    ``pattern`` ``<axis><R|T|A|X|Y|Z>`` of the machine; ``setup = "<id>"`` or ``R_B_mm`` of a new tool length;
    ``mount = "<id>"`` or ``position_mm = [x, y, z]`` of a new W-ball placement; optional ``arc_deg = [start, end,
    step]`` (default the axis' grid), ``hold_deg = {letter = degrees}`` (the other rotary axes), ``length_mm``,
    ``repeats`` and ``name``.  Its travels are checked with the catalogue's (:func:`described_feasibility_check`)."""
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
