"""The candidate ball-bar runs of any machine, from its description (SPEC §6, §19, §20; docs/design.md).

One catalogue serves every machine.  For the campaign's primary set-up ``T`` and the W-ball mounts each pattern
may use (:attr:`CatalogueRules.pattern_mounts`: by default every mount of the campaign):

* every pattern ``<K><d>`` the machine has (its plug-in's, else :func:`~mtmcal_bayes.machines.patterns.patterns_of`)
  over its arc, the other rotary axes at 0, where the campaign has not measured it;
* the same with the other rotary axes **held** at :data:`HOLD_DEG` (the first of them within the axis' travel),
  where the machine's runs may hold them (:attr:`CatalogueRules.hold`);
* tool lengths ``R_B + e`` for the rules' extensions (a new set-up with its own T-ball offsets,
  :attr:`CatalogueRules.extended_setup`) and the campaign's unmeasured set-ups;
* the W ball at other **placements** (:attr:`CatalogueRules.placements`: by default :data:`PLACEMENTS_MM` added to
  the first mount's position; each its own W-ball offsets);
* more repeats of the measured runs, and other bar lengths (for ``plan``; a design keeps the campaign's bar).

A machine's plug-in may state its campaign format's own rules through its planning kit
(:mod:`.machine_kit`): the thesis' Step 5 extension bars with ``Z_T − e``, its other R_C, its bar lengths, the
W ball on the C axis for B patterns (Table 2.2), its published labels.  The catalogue asks the rules, never which
kind of machine it holds.

Every candidate is checked (:func:`feasibility_check`) with the engine's commands of the run
(:func:`~mtmcal_bayes.machines.patterns.pattern_commands`, placed as the machine's plug-in places its runs where it
does): against each described travel (rotary and linear, absolute), and against the span of each axis travel the
campaign's ``[machine]`` gives without saying where the axes sit in it.  A pattern whose bar has no direction (the
ball on the swivelled axis' line) is no measurement and is infeasible.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..campaign import Mount, Setup
from ..io.machine_reader import description_of
from ..machines.patterns import pattern_commands, patterns_of
from ..machines.plugins import provided
from .candidates import DEFAULT_REPEATS, Candidate
from .chain_candidates import arc_of, arc_spec

#: tool-length extensions of the engine's catalogue, mm
EXTENSIONS_MM = (50.0, 100.0, 150.0)
#: held positions tried for the other rotary axes, degrees (the first within the axis' travel is taken)
HOLD_DEG = (90.0, -90.0, 45.0, -45.0, 30.0, -30.0)
#: other W-ball placements of the engine's catalogue: offsets from the first mount's position, mm
PLACEMENTS_MM = ((50.0, 0.0, 0.0), (0.0, 50.0, 0.0), (0.0, 0.0, 100.0))
#: other bar lengths of the engine's catalogue (``plan`` only), mm
OTHER_L_B_MM = (150.0,)


def new_tool_setup(base: Setup, extension: float) -> Setup:
    """A set-up ``extension`` mm longer than ``base`` (only its tool length R_B enters the chain)."""
    return Setup(f"{base.id}+{extension:g}", base.R_B + extension, 0.0, 0.0)


def every_mount(campaign, patterns) -> list[tuple[str, Mount]]:
    """``(pattern, mount)`` for every mount of the campaign (mount by mount) and every pattern."""
    return [(p, w) for w in campaign.ballbar.mounts.values() for p in patterns]


def placed_from_first(campaign) -> list[tuple[str, str, Mount, tuple[str, ...] | None]]:
    """The W ball moved by each of :data:`PLACEMENTS_MM` from the first mount: ``(kind, label, mount, patterns)``,
    every pattern (None)."""
    first = next(iter(campaign.ballbar.mounts.values()))
    out = []
    for k, off in enumerate(PLACEMENTS_MM):
        m = Mount(f"{first.id}@{k + 1}", 0.0, 0.0, position=first.centre() + off)
        shift = ", ".join(f"{a}{v:+g}" for a, v in zip("XYZ", off) if v)
        out.append(("other placement", f"W ball {shift} mm", m, None))
    return out


@dataclass(frozen=True)
class CatalogueRules:
    """What a campaign format lets the catalogue vary (the defaults: the engine's, for a machine from its
    description).

    ``extensions_mm`` the tool-length extensions; ``tool_length_patterns`` the patterns measured at other tool
    lengths and unmeasured set-ups (None: every pattern); ``bar_lengths_mm`` and ``bar_length_patterns`` the other
    bars; ``hold`` whether a run may hold the other rotary axes away from 0; ``label_mount`` whether labels name
    the mount; ``extended_setup(base, e) -> Setup``; ``pattern_mounts(campaign, patterns) -> [(pattern, Mount)]``
    the mounts each pattern may use, in catalogue order (a pattern's first is its mount for the sweep and the bar
    lengths); ``placements(campaign) -> [(kind, label, Mount, patterns or None)]`` the other W-ball placements;
    ``probe_positions`` {rotary axis letter: angles, degrees} where the format indexes an axis' probe runs at
    positions of its own (else the engine's, from the axis' travel: :mod:`.probe_catalogue`)."""

    extensions_mm: tuple[float, ...] = EXTENSIONS_MM
    tool_length_patterns: tuple[str, ...] | None = None
    bar_lengths_mm: tuple[float, ...] = OTHER_L_B_MM
    bar_length_patterns: tuple[str, ...] | None = None
    hold: bool = True
    label_mount: bool = True
    extended_setup: Callable = new_tool_setup
    pattern_mounts: Callable = every_mount
    placements: Callable = placed_from_first
    probe_positions: tuple[tuple[str, tuple[float, ...]], ...] = ()


def rules_of(campaign) -> CatalogueRules:
    """The catalogue rules of ``campaign``'s machine: its plug-in's planning kit's (:mod:`.machine_kit`), else the
    engine's."""
    kit = provided(campaign.machine, "planning")
    return CatalogueRules() if kit is None else kit.catalogue_rules


def patterns_for(campaign) -> list[str]:
    """The patterns of ``campaign``'s machine: its plug-in's (in its order), else every ``<K><d>`` of its chain."""
    machine = campaign.machine
    return list(provided(machine, "patterns") or patterns_of(description_of(machine)))


def holds_within(ax) -> tuple[float, ...]:
    """The angles of :data:`HOLD_DEG` a rotary axis' travel allows (all where it states none), in their order."""
    lo, hi = (-np.inf, np.inf) if ax.travel is None else np.rad2deg(ax.travel)
    return tuple(h for h in HOLD_DEG if lo - 1e-9 <= h <= hi + 1e-9)


def hold_for(desc, letter: str) -> tuple[tuple[str, float], ...] | None:
    """The other rotary axes of a pattern of axis ``letter`` held at the first of :data:`HOLD_DEG` each allows;
    None when no other rotary axis has such a position."""
    held = tuple((ax.letter, holds_within(ax)[0]) for ax in desc.rotary_axes
                 if ax.letter != letter and holds_within(ax))
    return held or None


def label(pattern: str, setup: Setup, mount: Mount | None, *, hold=(), length: float | None = None) -> str:
    """``"CR @ T1/W1, A held at 90°, L_B 150 mm"`` (the mount left out when None)."""
    where = f"{pattern} @ {setup.id}" + ("" if mount is None else f"/{mount.id}")
    if hold:
        where += ", " + ", ".join(f"{a} held at {v:g}°" for a, v in hold)
    if length is not None:
        where += f", L_B {length:g} mm"
    return where


def catalogue(campaign) -> list[Candidate]:
    """The candidate runs of ``campaign`` (module docstring), feasible or not, in catalogue order."""
    rules = rules_of(campaign)
    desc = description_of(campaign.machine)
    bb = campaign.ballbar
    base = campaign.primary_setup()
    L = bb.length
    pats = patterns_for(campaign)
    pairs = rules.pattern_mounts(campaign, pats)
    first = dict(reversed(pairs))  # each pattern's first mount
    first_mount = next(iter(bb.mounts.values()), None)

    def shown(w: Mount) -> Mount | None:  # the mount as labels name it (a format whose patterns fix it: none)
        return w if rules.label_mount else None

    out: list[Candidate] = []

    def add(name, kind, pattern, setup, *, m, length=L, hold=(), repeat_of=None, arc=None, extension=None):
        # a new run's tool-length extension over the primary set-up; a repeat of a measured run has none
        if extension is None and repeat_of is None:
            extension = setup.R_B - base.R_B
        out.append(Candidate(name, kind, pattern, setup, m, length, DEFAULT_REPEATS, repeat_of, extension, arc,
                             tuple(hold or ())))

    measured = {(r.pattern, r.setup, r.mount, tuple(sorted((r.hold_deg or {}).items()))) for r in bb.runs}
    for p, w in pairs:
        if (p, base.id, w.id, ()) not in measured:
            add(label(p, base, shown(w)), "other pattern", p, base, m=w)
        hold = rules.hold and hold_for(desc, p[0])
        if hold and (p, base.id, w.id, tuple(sorted(hold))) not in measured:
            add(label(p, base, shown(w), hold=hold), "held axes", p, base, m=w, hold=hold)
    lengths = pairs if rules.tool_length_patterns is None else \
        [(p, w) for q in rules.tool_length_patterns for p, w in pairs if p == q]
    by_mount: dict[str, list[tuple[str, Mount]]] = {}
    for p, w in lengths:
        by_mount.setdefault(w.id, []).append((p, w))
    # an extension to an existing set-up's tool length is that set-up's (its candidates below): a second set-up of one
    # length is refused by the campaign format (a designed campaign naming one could not be read back)
    lengths_now = {s.R_B for s in bb.setups.values()}
    for group in by_mount.values():  # mount by mount: its tool lengths, extension by extension, its unmeasured set-ups
        for e in rules.extensions_mm:
            if rules.extended_setup(base, e).id not in bb.setups and rules.extended_setup(base, e).R_B in lengths_now:
                continue
            for p, w in group:
                where = "" if not rules.label_mount or w is first_mount else f", mount {w.id}"
                add(f"{p} @ R_B+{e:g} mm{where}", "tool length", p, rules.extended_setup(base, e), m=w, extension=e)
        for s in bb.setups.values():
            if s.id != base.id:
                for p, w in group:
                    if (p, s.id, w.id, ()) not in measured:
                        add(label(p, s, shown(w)) + " (existing setup)", "existing setup", p, s, m=w)
    for kind, text, m, only in rules.placements(campaign):
        for p in only or pats:
            add(f"{p} @ {base.id}, {text}", kind, p, base, m=m)
    for i, run in enumerate(bb.runs):
        hold = tuple((run.hold_deg or {}).items())
        add(f"repeat {label(run.pattern, bb.setups[run.setup], bb.mounts[run.mount], hold=hold)} "
            f"(+{DEFAULT_REPEATS})", "repeats", run.pattern, bb.setups[run.setup], m=bb.mounts[run.mount], hold=hold,
            repeat_of=i, arc=arc_spec(run.arc_deg))
    for L_B in rules.bar_lengths_mm:
        if L_B != L:
            for p in rules.bar_length_patterns or pats:
                add(label(p, base, shown(first[p]), length=L_B), "bar length", p, base, m=first[p], length=L_B)
    return out


def sweep_candidates(campaign, pattern: str, extensions) -> list[Candidate]:
    """``pattern`` at the primary set-up plus each extension (mm), at the pattern's first mount: the tool-length
    sweep."""
    rules = rules_of(campaign)
    base = campaign.primary_setup()
    _, mount = rules.pattern_mounts(campaign, [pattern])[0]
    return [Candidate(f"{pattern} @ R_B+{e:g} mm", "sweep", pattern, rules.extended_setup(base, e), mount,
                      campaign.ballbar.length, extension=float(e)) for e in extensions]


def feasibility_check(campaign):
    """``check(candidate) -> (feasible, why)``: whether a candidate's commands fit the machine's travels.

    The commands are the engine's (:func:`~mtmcal_bayes.machines.patterns.pattern_commands`), the run placed as the
    machine's plug-in places its runs where it does (``run_placement``: the thesis' W balls, arcs and bar sides of
    Tables 2.2/2.3), else at its mount's position over its arc.  Each command must lie within its axis' described
    travel; an axis travel the campaign's ``[machine]`` gives as a length only (it does not say where the axis sits
    in it) must hold the span of the axis' commands.  The campaign is read once, here, for every candidate checked.
    """
    machine = campaign.machine
    desc = description_of(machine)
    spans = dict(machine.travel or {})
    place = provided(machine, "run_placement")
    limited = bool(spans) or any(ax.travel is not None for ax in desc.axes.values())

    def placed(c: Candidate):
        if place is not None and c.arc_deg is None and not c.hold_deg:
            return place(campaign, c.pattern, c.mount)
        return c.mount.centre(), arc_of(c, desc), False

    def check(c: Candidate) -> tuple[bool, str]:
        if not limited:
            return True, "no axis travels in [machine]: not checked"
        ball, arc, reverse = placed(c)
        try:
            cmd = pattern_commands(desc, c.pattern, length=c.setup.R_B, ball=ball, bar=c.length, arc_deg=arc,
                                   hold_deg=dict(c.hold_deg) or None, reverse=reverse)
        except ValueError as err:
            return False, str(err)
        over = travel_overruns(desc, cmd.q)
        for axis in "XYZ":
            span = float(np.ptp(cmd.q[axis]))
            if axis in spans and span > spans[axis] + 1e-9:
                over.append(f"{axis} span {span:.0f} mm > travel {spans[axis]:g} mm")
        return (not over), ("; ".join(over) if over else "within the axis travels")

    return check


def feasibility(candidate: Candidate, campaign) -> tuple[bool, str]:
    """Whether the candidate's commands fit the machine's travels, and why not (:func:`feasibility_check`)."""
    return feasibility_check(campaign)(candidate)


def travel_overruns(desc, q: dict) -> list[str]:
    """Each command of ``q`` {letter: (k,) mm or rad} beyond its described travel, as a phrase."""
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
    return over


def travel_problems(desc, q: dict) -> tuple[bool, str]:
    """Whether commands ``q`` {letter: (k,) mm or rad} stay within every described travel, and why not."""
    over = travel_overruns(desc, q)
    return (not over), ("; ".join(over) if over else "within the axis travels")


__all__ = ["EXTENSIONS_MM", "HOLD_DEG", "OTHER_L_B_MM", "PLACEMENTS_MM", "CatalogueRules", "catalogue", "feasibility",
           "feasibility_check", "hold_for", "label", "patterns_for", "rules_of", "sweep_candidates", "travel_problems"]
