"""The machine-time model applied to designed runs: measuring order, minutes, the schedule's events.

A design measures instrument by instrument — the ball bar's runs (grouped by set-up and placement), then the touch
probe's, then the R-test's — each instrument after the first costing ``instrument_change_min`` and its own set-up
(``mount_probe_min``, ``mount_rtest_min``); a probe run at another stylus length or sphere position than the one
before costs ``stylus_change_min`` / ``move_sphere_min``, and so does a further run of one probe candidate (its
stylus and sphere are set anew: their terms are its own, :meth:`.candidates.WithoutBar.again`).  A probe run
measures ``repeats × positions × probe_position_min``, an R-test run its positions or its sweep
(:func:`~mtmcal_bayes.machine_time.rtest_run_minutes`).

The machine's state at the start, ``start`` = (ball bar mounted, set-up id, mount id[, other]): ``other`` (``next``
after a probe or R-test run, :func:`.next_run.machine_state`) the instrument on the machine instead of the ball bar,
``("probe", stylus length, sphere)`` or ``("rtest",)``: that instrument's runs are measured first (its set-up is not
counted again, a probe run at its stylus and sphere costs no change), then the ball bar's, whose first run costs
``instrument_change_min`` before the bar's own set-up, then the other instrument's.
"""

from __future__ import annotations

import numpy as np

from ..machine_time import Event, Schedule, TimeModel, canonical_order, probe_run_minutes, rtest_run_minutes
from .machine_kit import kit_of

#: the order in which a session measures the instruments
SESSION = ("ballbar", "probe", "rtest")
#: a new session: nothing mounted
NEW = (False, None, None)


def other_on(start) -> tuple | None:
    """The probe or R-test state ``start`` has on the machine (module docstring), None where it has none."""
    return start[3] if len(start) > 3 else None


class Timing:
    """Minutes of runs at ``campaign``'s geometry (bar length, CR geometry, feed) under ``model``.

    ``start`` = (ball bar mounted, current setup id, current mount id); runs are measured in
    :func:`~mtmcal_bayes.machine_time.canonical_order` unless already ordered (:meth:`per_run`, :meth:`events`).
    """

    def __init__(self, campaign, model: TimeModel):
        self.model = model
        self.clock = kit_of(campaign).clock(model, campaign)

    def order(self, runs, start) -> list[int]:
        """The measuring order: the runs of a probe or an R-test already on the machine (``start``) first, then the
        ball bar's by set-up and placement, then the probe's by stylus and sphere, then the R-test's (module
        docstring)."""
        bar = [i for i, r in enumerate(runs) if r.instrument == "ballbar"]
        probe = [i for i, r in enumerate(runs) if r.instrument == "probe"]
        keys = list(dict.fromkeys(_probe_key(runs[i].candidate) for i in probe))
        by = {"ballbar": [bar[j] for j in canonical_order([runs[i] for i in bar], start[1], start[2])],
              "probe": sorted(probe, key=lambda i: keys.index(_probe_key(runs[i].candidate))),
              "rtest": [i for i, r in enumerate(runs) if r.instrument == "rtest"]}
        return [i for instrument in _session(start) for i in by[instrument]]

    def total(self, runs, start) -> float:
        """Minutes of ``runs`` in their measuring order (the schedule's events added one by one, in order)."""
        t = 0.0
        for e in self.schedule([runs[i] for i in self.order(runs, start)], start).events:
            t += e.minutes
        return t

    def _bar_events(self, bar, start) -> list[Event]:
        """The schedule's events of the ball bar's runs ``bar`` (in order) from ``start``: with a probe or an R-test on
        the machine, the change of instrument first, then the bar's set-up as in a new session."""
        if other_on(start) is None:
            return list(self.clock.schedule(bar, start[:3]).events)
        if not bar:
            return []
        change = self.model.instrument_change_min
        events = self.clock.schedule(bar, NEW).events
        return [Event("change instrument", 0, 0.0, change, events[0].label)] + [
            Event(e.kind, e.run_index, e.start_min + change, e.minutes, e.label) for e in events]

    def per_run(self, runs, start) -> list[float]:
        """Minutes of each run of the ordered ``runs``: measuring plus the set-up changes before it."""
        return self.schedule(runs, start).run_total_min(len(runs))

    def events(self, runs, start):
        """The schedule's events of the ordered ``runs``."""
        return self.schedule(runs, start).events

    def schedule(self, runs, start) -> Schedule:
        """The schedule of the ordered ``runs`` (as :meth:`order` puts them: the runs of a probe or an R-test on the
        machine, then the ball bar's, then the other instruments')."""
        bar_at = [j for j, r in enumerate(runs) if r.instrument == "ballbar"]
        if len(bar_at) == len(runs) and other_on(start) is None:
            return self.clock.schedule(runs, start[:3])
        first = bar_at[0] if bar_at else len(runs)
        end = first + len(bar_at)
        events, t = [], 0.0
        for j, kind, minutes in self._other_steps(runs[:first], _current(start, False)):
            events.append(Event(kind, j, t, minutes, runs[j].label))
            t += minutes
        # the bar after the instrument on the machine: a change of instrument, then its set-up as in a new session
        bar_start = (False, None, None, (runs[first - 1].instrument,)) if first else start
        t_bar = t
        for e in self._bar_events(runs[first:end], bar_start):
            events.append(Event(e.kind, first + e.run_index, t_bar + e.start_min, e.minutes, e.label))
            t += e.minutes
        for j, kind, minutes in self._other_steps(runs[end:], ("ballbar",)):
            events.append(Event(kind, end + j, t, minutes, runs[end + j].label))
            t += minutes
        return Schedule(events)

    def _other_steps(self, runs, current: tuple | None):
        """``(index, kind, minutes)`` of the probe's and the R-test's runs ``runs`` (in order) after the ball bar's;
        ``current`` the instrument on the machine before them (:func:`_current`; None: nothing mounted)."""
        m = self.model
        current, stylus, sphere = (current[0], current[1], tuple(current[2])) if current and current[0] == "probe" \
            else (current[0] if current else None, None, None)
        for j, r in enumerate(runs):
            c = r.candidate
            if r.instrument != current:
                if current is not None:
                    yield j, "change instrument", m.instrument_change_min
                yield j, f"mount {'probe' if r.instrument == 'probe' else 'R-test'}", \
                    m.mount_probe_min if r.instrument == "probe" else m.mount_rtest_min
                current = r.instrument
                if r.instrument == "probe":
                    stylus, sphere = c.stylus_length, tuple(c.sphere)
            if r.instrument == "probe":
                again = _further(r)  # its stylus and sphere set anew
                if again or c.stylus_length != stylus:
                    yield j, "stylus change", m.stylus_change_min
                if again or tuple(c.sphere) != sphere:
                    yield j, "move sphere", m.move_sphere_min
                stylus, sphere = c.stylus_length, tuple(c.sphere)
            yield j, "measure", self._other_minutes(c)

    def _other_minutes(self, c) -> float:
        """Measuring minutes of one probe or R-test run of candidate ``c`` (its set-up counted apart), each
        candidate's once (the search walks its schedule hundreds of thousands of times)."""
        cache = self.__dict__.setdefault("_other_measured", {})
        if id(c) not in cache:
            minutes = probe_run_minutes(self.model, len(c.positions[0][1]), c.repeats, set_up=False) \
                if c.instrument == "probe" else \
                rtest_run_minutes(self.model, c.n_positions, c.repeats, sweep_span_deg=c.sweep_span, set_up=False)
            cache[id(c)] = (c, minutes)  # c kept: its id stays its own
        return cache[id(c)][1]

    def total_of_counts(self, candidates, counts, start) -> float:
        """:meth:`total` of the runs of ``counts`` (K,) of ``candidates`` (as :func:`.design_runs.designed_runs`
        makes them: a candidate's further runs each on a placement of its own) without making them: the same
        schedule walked over (set-up, placement) keys, its minutes added in the same order (the same float).  The
        search asks this tens of thousands of times; walking stand-in runs through :func:`canonical_order` and
        ``MachineClock._steps`` took half as long again over a whole design, so the walk is written out here
        (``tests/test_machine_time.py`` holds it equal to :meth:`total`)."""
        # the ball bar's runs grouped by set-up, then placement, each in the order of first appearance (designed
        # order); the probe's and the R-test's runs apart, as :meth:`order` puts them
        setup_of, mount_of, measure = self._keys(candidates)
        groups: dict = {}
        others = []  # (candidate, runs) of the probe's and the R-test's
        nz = np.flatnonzero(counts)
        for k, n in zip(nz.tolist(), np.asarray(counts)[nz].tolist()):
            if measure[k] is None:
                others.append((k, n))
                continue
            by_mount = groups.setdefault(setup_of[k], {})
            by_mount.setdefault(mount_of[k], []).append(k)
            for i in range(1, n):
                by_mount[("again", k, i)] = [k]
        setups = list(groups)
        if start[1] in groups:
            setups.remove(start[1])
            setups.insert(0, start[1])
        m = self.model
        t = 0.0
        # the runs of the probe or the R-test on the machine first (:meth:`order`), the others after the bar's
        pre, rest = self._other_entries(candidates, others, start) if others else ([], [])
        if pre and groups:
            t = self._others_after(t, candidates, pre, _current(start, False))
        elif pre:
            rest = pre + rest  # no bar run between them: one walk
        if groups and other_on(start) is not None:  # the probe or the R-test on the machine: changed for the bar
            t += m.instrument_change_min
            mounted, setup, mount = NEW
        else:
            mounted, setup, mount = start[:3]
        for s in setups:
            mounts = list(groups[s])
            if s == start[1] and start[2] in groups[s]:
                mounts.remove(start[2])
                mounts.insert(0, start[2])
            for mt in mounts:
                ks = groups[s][mt]
                # the group's first run after whatever came before; the others each a pattern change (the same
                # additions, in the same order, as the schedule's walk)
                if not mounted:
                    t += m.mount_ballbar_min
                if s != setup:
                    t += m.tool_change_min
                if mt != mount:
                    t += m.reclamp_w_ball_min
                if mounted and s == setup and mt == mount:
                    t += m.pattern_change_min
                t += measure[ks[0]]
                for k in ks[1:]:
                    t += m.pattern_change_min
                    t += measure[k]
                mounted, setup, mount = True, s, mt
        if rest:
            t = self._others_after(t, candidates, rest, ("ballbar",) if groups else _current(start, False))
        return t

    def _other_entries(self, candidates, others: list[tuple[int, int]], start) -> tuple[list, list]:
        """The probe's and the R-test's runs ``others`` ((candidate, runs), in candidate order) as ``(candidate,
        instance)`` in :meth:`order`'s order: those of the instrument on the machine (``start``), and the rest."""
        inst, key = self._other_keys(candidates)[:2]
        rank: dict = {}
        probe = [(k, i) for k, n in others if inst[k] == "probe" for i in range(1, n + 1)]
        for k, _ in probe:
            rank.setdefault(key[k], len(rank))
        probe.sort(key=lambda e: rank[key[e[0]]])  # by stylus and sphere in order of first appearance (stable)
        by = {"probe": probe, "rtest": [(k, i) for k, n in others if inst[k] == "rtest" for i in range(1, n + 1)]}
        on = other_on(start)
        pre = by.pop(on[0]) if on is not None and on[0] in by else []
        return pre, [e for i in ("probe", "rtest") if i in by for e in by[i]]

    def _others_after(self, t: float, candidates, entries: list[tuple[int, int]], current: tuple | None) -> float:
        """``t`` plus the minutes of the probe's and the R-test's runs ``entries`` ((candidate, instance), in
        measuring order) from ``current`` (:func:`_current`): :meth:`_other_steps`' additions, in the same order (the
        same float), without making runs."""
        inst, key, stylus, sphere, minutes, renamed = self._other_keys(candidates)
        m = self.model
        current, sty, sph = (current[0], current[1], tuple(current[2])) if current and current[0] == "probe" \
            else (current[0] if current else None, None, None)
        for k, i in entries:
            if inst[k] != current:
                if current is not None:
                    t += m.instrument_change_min
                t += m.mount_probe_min if inst[k] == "probe" else m.mount_rtest_min
                current = inst[k]
                if current == "probe":
                    sty, sph = stylus[k], sphere[k]
            if current == "probe":
                again = i > 1 or renamed[k]  # its stylus and sphere set anew (:func:`_further`)
                if again or stylus[k] != sty:
                    t += m.stylus_change_min
                if again or sphere[k] != sph:
                    t += m.move_sphere_min
                sty, sph = stylus[k], sphere[k]
            t += minutes[k]
        return t

    def _other_keys(self, candidates) -> tuple[list, ...]:
        """Per candidate of ``candidates``: its instrument, its probe key (stylus length, sphere), stylus length,
        sphere, measuring minutes and whether it is a further run by its id (:func:`_further`); None for a ball-bar
        candidate; made once per list of candidates."""
        cache = self.__dict__.setdefault("_other_keyed", {})
        if id(candidates) not in cache:
            probe = [c if c.instrument == "probe" else None for c in candidates]
            other = [c if c.instrument != "ballbar" else None for c in candidates]
            cache[id(candidates)] = (candidates, (
                [c.instrument for c in candidates],
                [None if c is None else _probe_key(c) for c in probe],
                [None if c is None else c.stylus_length for c in probe],
                [None if c is None else tuple(c.sphere) for c in probe],
                [None if c is None else self._other_minutes(c) for c in other],
                [c is not None and _renamed(c) for c in other]))
        return cache[id(candidates)][1]

    def floor(self, candidates) -> np.ndarray:
        """(K,) the fewest minutes one more run of each of ``candidates`` adds to any schedule: its measuring minutes
        (set-up changes, pattern changes and instrument changes come on top)."""
        return np.array([self._measure(c) if c.instrument == "ballbar" else self._other_minutes(c)
                         for c in candidates])

    def _keys(self, candidates) -> tuple[list, list, list]:
        """Per candidate of ``candidates``: its set-up id, its mount id and its measuring minutes (None: a probe or
        R-test candidate), made once per list of candidates."""
        cache = self.__dict__.setdefault("_keyed", {})
        if id(candidates) not in cache:
            bar = [c.instrument == "ballbar" for c in candidates]
            cache[id(candidates)] = (candidates, (
                [c.setup.id if b else None for c, b in zip(candidates, bar)],
                [c.mount.id if b else None for c, b in zip(candidates, bar)],
                [self._measure(c) if b else None for c, b in zip(candidates, bar)]))  # candidates kept: ids stay
        return cache[id(candidates)][1]

    def _measure(self, c) -> float:
        """Measuring minutes of one run of candidate ``c`` (every run of it alike), each candidate's once."""
        cache = self.__dict__.setdefault("_measured", {})
        if id(c) not in cache:
            cache[id(c)] = (c, self.clock.run_minutes(_AsRun(c)))  # c kept: its id stays its own
        return cache[id(c)][1]


class _AsRun:
    """A candidate seen as a run of a schedule (pattern, set-up, mount, repeats, candidate)."""

    def __init__(self, c):
        self.candidate, self.pattern, self.setup, self.mount, self.repeats = c, c.pattern, c.setup, c.mount, c.repeats


class _Other:
    """A probe or R-test candidate's ``instance``-th run seen as a run of a schedule."""

    def __init__(self, c, instance: int):
        self.candidate, self.instance, self.instrument = c, instance, c.instrument


def _further(r) -> bool:
    """Whether ``r`` is a further run of one probe candidate: its ``instance`` > 1, or a run ``next`` plans as one
    (:func:`_renamed`)."""
    return r.instance > 1 or _renamed(r.candidate)


def _renamed(c) -> bool:
    """Whether candidate ``c`` is the catalogue's as a further run of itself (owners ``<id>#<k>``:
    :meth:`.candidates.WithoutBar.again`)."""
    head, sep, k = c.id.rpartition("#")
    return bool(head and sep and k.isdigit())


def _session(start) -> tuple[str, ...]:
    """The order of the instruments from ``start``: a probe or an R-test on the machine first, then :data:`SESSION`'s."""
    on = other_on(start)
    return SESSION if on is None or on[0] not in SESSION else (on[0],) + tuple(i for i in SESSION if i != on[0])


def _current(start, bar: bool) -> tuple | None:
    """The instrument on the machine when the probe's and the R-test's runs begin: the ball bar after its runs
    (``bar``) or where ``start`` has it mounted, else ``start``'s probe or R-test (None: nothing)."""
    if bar or start[0]:
        return ("ballbar",)
    return other_on(start)


def _probe_key(c) -> tuple:
    """Probe runs measured one after the other without a change: the same stylus length and sphere position."""
    return (c.stylus_length, tuple(c.sphere))
