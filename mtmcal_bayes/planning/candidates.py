"""Candidate additional measurements and their feasibility (SPEC §6).

A candidate is one ball-bar run that could be added to a campaign: a pattern
at a tool setup and a W-ball mount with a bar length, measured ``repeats``
times; or more repeats of a run the campaign already has.  New tool setups
follow the thesis' extension-bar procedure (Step 5, Table 4.3): an extension
of ``e`` mm gives ``R_B + e`` and ``Z_T − e`` (R_B + Z_T stays constant: the
spindle head moves back by the extension), ``X_T`` unchanged.  A new setup or
mount brings its own nuisance offsets (a re-centred ball, a re-clamped ball).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..campaign import Campaign, Mount, Setup
from ..errors import ParameterError
from ..io.machine_reader import description_of
from ..io.textfiles import read_user_text
from ..io.toml_reader import TomlReader, parse_toml
from ..machines.patterns import pattern_commands
from ..machines.plugins import provided
from ..patterns import PATTERNS, mount_conflict

#: extension bars of the catalogue, mm
EXTENSIONS_MM = (25.0, 50.0, 75.0, 100.0, 125.0, 150.0)
#: other W-ball radii and bar lengths of the catalogue, mm
OTHER_R_C_MM = (50.0, 100.0, 150.0)
OTHER_L_B_MM = (50.0, 100.0, 150.0)
#: patterns measured at additional tool lengths
TOOL_LENGTH_PATTERNS = ("CR", "CA", "BX", "BY")
DEFAULT_REPEATS = 3
#: most repeats of a user candidate: beyond a few hundred, s²/n is far below u_inst² + sigma_model², which do not
#: average out, so more repeats add nothing; 1e20 would overflow the planner's arrays (docs/planning.md)
MAX_REPEATS = 10_000
#: largest |length| of a user candidate, mm (lever arms, mount, bar length): 10 m is beyond the travels of any
#: turn-mill machine; larger numbers are unit slips and make the design matrix singular (docs/planning.md)
MAX_LENGTH_MM = 10_000.0


@dataclass(frozen=True)
class Candidate:
    """One candidate measurement.

    ``setup``/``mount`` carry the geometry (mm); their ids name the nuisance
    parameters, so a candidate at an existing setup shares its offsets.
    ``repeat_of`` is the index of the campaign run it repeats (``None`` for a
    new run); ``extension`` the tool-length difference to the primary setup, mm; ``arc_deg``, ``hold_deg``
    a described machine's arc and held axes (:mod:`.chain_candidates`).
    """

    name: str
    kind: str
    pattern: str
    setup: Setup
    mount: Mount
    length: float
    repeats: int = DEFAULT_REPEATS
    repeat_of: int | None = None
    extension: float | None = None
    #: a described machine's run: the swivelled axis' arc ``(start, end, step)`` degrees (None: the axis' default
    #: grid) and the held rotary axes ``((letter, degrees), ...)``
    arc_deg: tuple[float, float, float] | None = None
    hold_deg: tuple[tuple[str, float], ...] = ()


def candidate_mount(campaign: Campaign, pattern: str) -> Mount:
    """The mount of a new run of ``pattern``: ``campaign.mount_for``, except that a B pattern measures with the W
    ball on the C axis (thesis Table 2.2) — without such a mount in the campaign, a new placement there
    (``<id>@R_C0``, at that mount's height, with its own W-ball offsets)."""
    m = campaign.mount_for(pattern)
    if mount_conflict(pattern, m.id, m.R_C):
        return Mount(f"{m.id}@R_C0", m.Z_C, 0.0)
    return m


def extended_setup(base: Setup, extension: float) -> Setup:
    """The tool setup with an extension bar of ``extension`` mm (Step 5 of the thesis)."""
    return Setup(f"{base.id}+{extension:g}", base.R_B + extension, base.Z_T - extension, base.X_T)


def catalogue(campaign: Campaign, extensions=EXTENSIONS_MM) -> list[Candidate]:
    """The default candidates: tool lengths, unmeasured setups, repeats, other patterns, R_C and L_B."""
    bb = campaign.ballbar
    base = campaign.primary_setup()
    L = bb.length
    mounts: dict[str, Mount] = {}

    def mount(pattern: str) -> Mount:  # the campaign asked once per pattern
        if pattern not in mounts:
            mounts[pattern] = candidate_mount(campaign, pattern)
        return mounts[pattern]

    out: list[Candidate] = []
    for pattern in TOOL_LENGTH_PATTERNS:
        for e in extensions:
            s = extended_setup(base, e)
            out.append(Candidate(f"{pattern} @ R_B+{e:g} mm", "tool length", pattern, s, mount(pattern),
                                 L, extension=e))
    measured = {(r.pattern, r.setup) for r in bb.runs}
    for s in bb.setups.values():
        for pattern in TOOL_LENGTH_PATTERNS:
            if (pattern, s.id) not in measured:
                out.append(Candidate(f"{pattern} @ {s.id} (existing setup)", "existing setup", pattern, s,
                                     mount(pattern), L, extension=s.R_B - base.R_B))
    for i, run in enumerate(bb.runs):
        out.append(Candidate(f"repeat {run.pattern} @ {run.setup}/{run.mount} (+{DEFAULT_REPEATS})", "repeats",
                             run.pattern, bb.setups[run.setup], bb.mounts[run.mount], L, repeat_of=i))
    done = {r.pattern for r in bb.runs}
    for pattern in PATTERNS:
        if pattern not in done:
            out.append(Candidate(f"{pattern} @ {base.id}", "other pattern", pattern, base,
                                 mount(pattern), L, extension=0.0))
    c_mount = campaign.mount_for("CR")
    for R_C in OTHER_R_C_MM:
        if R_C != c_mount.R_C:
            m = Mount(f"{c_mount.id}@R_C{R_C:g}", c_mount.Z_C, R_C)
            for pattern in ("CR", "CA"):
                out.append(Candidate(f"{pattern} @ {base.id}, R_C {R_C:g} mm", "other R_C", pattern, base, m, L,
                                     extension=0.0))
    for L_B in OTHER_L_B_MM:
        if L_B != L:
            for pattern in TOOL_LENGTH_PATTERNS:
                out.append(Candidate(f"{pattern} @ {base.id}, L_B {L_B:g} mm", "bar length", pattern, base,
                                     mount(pattern), L_B, extension=0.0))
    return out


def feasibility_check(campaign: Campaign):
    """``check(candidate) -> (feasible, why)``: whether a candidate's axis motions fit the machine's travels.

    The campaign gives each axis' travel, not where the C axis sits inside it,
    so a pattern is feasible when the span of each linear-axis command fits the
    travel.  The commands are the engine's (:func:`~mtmcal_bayes.machines.patterns.pattern_commands`) with the run
    placed as the machine's plug-in places it (``run_placement``: on the thesis machine the B-axis centre path of
    Tables 2.2/2.3).  The campaign is read once, here, for every candidate checked.
    """
    travel = dict(campaign.machine.travel or {})
    desc = description_of(campaign.machine)
    place = provided(campaign.machine, "run_placement")
    if place is None:
        raise ParameterError("campaign", "the span rule checks runs of a campaign format whose plug-in places them "
                             "(the thesis' lever arms); a described machine's candidates are checked against its "
                             "description's travels (planning.machine_kit.feasibility_of)")

    def check(candidate: Candidate) -> tuple[bool, str]:
        if not travel:
            return True, "no axis travels in [machine]: not checked"
        ball, arc, reverse = place(campaign, candidate.pattern, candidate.mount)
        cmd = pattern_commands(desc, candidate.pattern, length=candidate.setup.R_B, ball=ball, bar=candidate.length,
                               arc_deg=arc, reverse=reverse)
        over = []
        for axis in "XYZ":
            span = float(np.ptp(cmd.q[axis]))
            if axis in travel and span > travel[axis] + 1e-9:
                over.append(f"{axis} span {span:.0f} mm > travel {travel[axis]:g} mm")
        return (not over), ("; ".join(over) if over else "within the axis travels")

    return check


def feasibility(candidate: Candidate, campaign: Campaign) -> tuple[bool, str]:
    """Whether the pattern's axis motions fit the machine's travels, and why not (:func:`feasibility_check`)."""
    return feasibility_check(campaign)(candidate)


_USER_KEYS = {"name", "pattern", "setup", "mount", "R_B_mm", "Z_T_mm", "X_T_mm", "Z_C_mm", "R_C_mm", "length_mm",
              "repeats"}


def _existing(r: TomlReader, t: dict, key: str, *, path: str, known: dict, geometry: tuple[str, ...]):
    """The campaign's setup/mount named by ``key``, None when the candidate gives a new one by its ``geometry``
    keys (both is an error: which one counts would be a guess)."""
    if key not in t:
        return None
    if given := [g for g in geometry if g in t]:
        r.fail(f"{path}.{given[0]}", f"give either {key} = \"<id>\" or {', '.join(geometry)} of a new {key}, not both")
    oid = r.string(t, key, path)
    if oid not in known:
        r.fail(f"{path}.{key}", f"no {key} {oid!r} in the campaign (have {', '.join(known)})")
    return known[oid]


def _length(r: TomlReader, t: dict, key: str, path: str, **checks) -> float:
    """Length ``key`` of a candidate, mm: finite, within ±MAX_LENGTH_MM (``checks`` as ``TomlReader.number``)."""
    v = r.number(t, key, path, **checks)
    if abs(v) > MAX_LENGTH_MM:
        r.fail(f"{path}.{key}", f"{v:g} mm is beyond ±{MAX_LENGTH_MM:g} mm, more than any machine tool's travel "
               "(µm written for mm?)")
    return v


def read_candidates(path, campaign: Campaign) -> list[Candidate]:
    """Candidates defined by the user in a TOML file of ``[[candidate]]`` tables.

    Each gives ``pattern`` and either ``setup = "<id>"`` of the campaign or the
    lever arms ``R_B_mm``, ``Z_T_mm``, ``X_T_mm`` of a new setup; either
    ``mount = "<id>"`` or ``Z_C_mm``, ``R_C_mm`` of a new mount; optional
    ``length_mm`` (bar length, default the campaign's), ``repeats`` (default 3)
    and ``name``.
    """
    r, items = candidate_tables(path)
    bb = campaign.ballbar
    out = []
    for i, t in enumerate(items):
        path_i = f"candidate[{i}]"
        r.check_keys(t, _USER_KEYS, path_i)
        pattern = r.string(t, "pattern", path_i, required=True)
        if pattern not in PATTERNS:
            r.fail(f"{path_i}.pattern", f"unknown pattern {pattern!r} (expected one of {' '.join(PATTERNS)})")
        setup = _existing(r, t, "setup", path=path_i, known=bb.setups,
                          geometry=("R_B_mm", "Z_T_mm", "X_T_mm")) or Setup(
            f"user{i}", _length(r, t, "R_B_mm", path_i, positive=True), _length(r, t, "Z_T_mm", path_i),
            _length(r, t, "X_T_mm", path_i))
        mount = _existing(r, t, "mount", path=path_i, known=bb.mounts, geometry=("Z_C_mm", "R_C_mm")) or Mount(
            f"user{i}", _length(r, t, "Z_C_mm", path_i, nonnegative=True),
            _length(r, t, "R_C_mm", path_i, nonnegative=True))
        if conflict := mount_conflict(pattern, t.get("mount"), mount.R_C):
            r.fail(f"{path_i}.mount" if "mount" in t else f"{path_i}.R_C_mm", conflict)
        length, repeats, name = candidate_run(r, t, path_i, campaign, pattern=pattern, setup=setup, mount=mount)
        out.append(Candidate(name, "user", pattern, setup, mount, length, repeats,
                             extension=setup.R_B - campaign.primary_setup().R_B))
    return out


def candidate_tables(path) -> tuple[TomlReader, list[dict]]:
    """The reader and the ``[[candidate]]`` tables of a candidates file (one line naming the file and key when it
    has none, or one is not a table)."""
    doc = parse_toml(read_user_text(path, "candidates file"), str(path))
    r = TomlReader(str(path))
    r.check_keys(doc, {"candidate"}, "")
    items = doc.get("candidate")
    if not isinstance(items, list) or not items:
        r.fail("candidate", "expected one or more [[candidate]] tables")
    for i, t in enumerate(items):
        if not isinstance(t, dict):
            r.fail(f"candidate[{i}]", "expected a table")
    return r, items


def candidate_run(r: TomlReader, t: dict, path: str, campaign: Campaign, *, pattern: str, setup: Setup,
                  mount: Mount) -> tuple[float, int, str]:
    """``(bar length mm, repeats, name)`` of a candidate table, each checked (defaults: the campaign's bar, 3
    repeats, a name from pattern, set-up and mount)."""
    length = _length(r, t, "length_mm", path, required=False, positive=True, default=campaign.ballbar.length)
    repeats = r.number(t, "repeats", path, required=False, positive=True, default=DEFAULT_REPEATS)
    if repeats != int(repeats):
        r.fail(f"{path}.repeats", f"must be a whole number, got {repeats:g}")
    if repeats > MAX_REPEATS:
        r.fail(f"{path}.repeats", f"{repeats:g} is more than {MAX_REPEATS}: beyond a few hundred repeats the "
               "instrument accuracy and the model discrepancy, which do not average out, set the uncertainty")
    name = r.string(t, "name", path, default=f"{pattern} @ {setup.id}/{mount.id} (user)")
    return length, int(repeats), name
