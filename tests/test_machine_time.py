"""The machine-time model of a campaign (docs/design.md, "Machine time")."""

import math

import numpy as np
import pytest

from mtmcal_bayes.campaign import Mount, Setup
from mtmcal_bayes.errors import InputError
from mtmcal_bayes.io.times_reader import read_times, time_model_from_table
from mtmcal_bayes.machine_time import TimeModel, canonical_order, path_length
from mtmcal_bayes.patterns import B_PATTERNS, PATTERNS
from mtmcal_bayes.plugins.thesis.timing import TIMED_POINTS, thesis_clock

SETUP = Setup("T", 356.3945, 112.2877, 490.0)
LONG = Setup("T+100", 456.3945, 12.2877, 490.0)
W0 = Mount("B", 65.5, 0.0)
W150 = Mount("C", 65.5, 150.0)


class R:  # a run as the scheduler sees one
    def __init__(self, pattern, setup, mount, repeats=3):
        self.pattern, self.setup, self.mount, self.repeats = pattern, setup, mount, repeats


def _minutes(clock, pattern, setup, mount, repeats) -> float:
    return clock.run_minutes(R(pattern, setup, mount, repeats))


@pytest.mark.parametrize("pattern, expected", [
    ("BX", 356.3945 * math.pi / 2),  # the B-axis centre on an arc of radius R_B over 90°
    ("BZ", 356.3945 * math.pi / 2),
    ("CA", 2 * math.pi * 150.0),  # a circle of radius R_C in the table frame
    ("CX", 2 * math.pi * 150.0),
    ("CR", 2 * math.pi * 50.0),  # radius R_C − L_B (Table 2.3 geometry)
    ("CT", 2 * math.pi * math.hypot(150.0, 100.0)),
])
def test_path_length_is_the_programmed_relative_path(pattern, expected):
    R_C = 0.0 if pattern.startswith("B") else 150.0
    clock = thesis_clock(TimeModel(), L_B=100.0)
    got = path_length(clock.desc, clock.motion(R(pattern, SETUP, Mount("m", 65.5, R_C))))
    assert got == pytest.approx(expected, rel=1e-5)  # a polygon of 720 chords: relative error ~ (2π/720)²/24


def test_measuring_minutes_from_feed_or_the_rotary_bound():
    m = TimeModel()
    clock = thesis_clock(m, L_B=100.0, feed=1000.0)
    bx = _minutes(clock, "BX", SETUP, W0, 3)
    per_direction = max(356.3945 * math.pi / 2 / 1000.0, 90.0 / m.rotary_deg_per_min)
    assert bx == pytest.approx(m.dwell_min + 3 * 2 * per_direction, rel=1e-5)
    # CR with R_C = L_B: the T ball on the C axis, no relative path: the table's turn sets the time
    cr = _minutes(clock, "CR", SETUP, Mount("C100", 65.5, 100.0), 2)
    assert cr == pytest.approx(m.dwell_min + 2 * 2 * 360.0 / m.rotary_deg_per_min)
    slow = thesis_clock(TimeModel(feed_mm_per_min=100.0), L_B=100.0, feed=1000.0)
    assert _minutes(slow, "CA", SETUP, W150, 1) == pytest.approx(m.dwell_min + 2 * 2 * math.pi * 150.0 / 100.0,
                                                                         rel=1e-5)


def test_feed_defaults_to_the_campaigns_then_1000():
    assert thesis_clock(TimeModel(), L_B=100.0, feed=1500.0).feed_mm_per_min == 1500.0
    assert thesis_clock(TimeModel(), L_B=100.0, feed=None).feed_mm_per_min == 1000.0
    assert thesis_clock(TimeModel(feed_mm_per_min=800.0), L_B=100.0, feed=1500.0).feed_mm_per_min == 800.0


def test_schedule_counts_each_set_up_change_once():
    m = TimeModel()
    clock = thesis_clock(m, L_B=100.0, feed=1000.0)
    runs = [R("BX", SETUP, W0), R("BY", SETUP, W0), R("CR", SETUP, W150), R("CR", LONG, W150)]
    sched = clock.schedule(runs)  # a new machine: mount the bar, set the first tool and ball
    kinds = [e.kind for e in sched.events]
    assert kinds.count("mount ball bar") == 1
    assert kinds.count("tool change") == 2  # T, then T+100
    assert kinds.count("re-clamp W ball") == 2  # B, then C
    assert kinds.count("pattern change") == 1  # BY after BX at the same set-up and placement
    measuring = sum(_minutes(clock, r.pattern, r.setup, r.mount, r.repeats) for r in runs)
    expected = measuring + m.mount_ballbar_min + 2 * m.tool_change_min + 2 * m.reclamp_w_ball_min + m.pattern_change_min
    assert sched.total_min == pytest.approx(expected)
    assert sum(sched.run_total_min(len(runs))) == pytest.approx(sched.total_min)
    # continuing at the last set-up and placement: no bar mounting, no change before the first run
    cont = clock.schedule(runs[3:], start=(True, "T+100", "C"))
    assert [e.kind for e in cont.events] == ["pattern change", "measure"]
    starts = [e.start_min for e in sched.events]
    assert starts == sorted(starts) and starts[0] == 0.0


def test_canonical_order_groups_set_ups_then_placements():
    runs = [R("BX", SETUP, W0), R("CR", LONG, W150), R("CA", SETUP, W150), R("BY", LONG, W0), R("BY", SETUP, W0)]
    order = canonical_order(runs)
    assert order == [0, 4, 2, 1, 3]
    clock = thesis_clock(TimeModel(), L_B=100.0, feed=1000.0)
    grouped = clock.schedule([runs[i] for i in order]).total_min
    assert grouped < clock.schedule(runs).total_min
    # the current set-up and placement first
    assert canonical_order(runs, "T+100", "B")[:2] == [3, 1]


def test_times_file_overrides_and_keeps_defaults(tmp_path):
    f = tmp_path / "times.toml"
    f.write_text("tool_change_min = 12\nfeed_mm_per_min = 1500\n", encoding="utf-8")
    m = read_times(f)
    assert m.tool_change_min == 12 and m.feed_mm_per_min == 1500
    assert m.reclamp_w_ball_min == TimeModel().reclamp_w_ball_min


@pytest.mark.parametrize("text, key", [
    ("tool_change_min = -1", "tool_change_min"),
    ("dwell_min = 'nan'", "dwell_min"),
    ("dwell_min = nan", "dwell_min"),
    ("mount_ballbar_min = 900", "mount_ballbar_min"),
    ("directions = 3", "directions"),
    ("feed_mm_per_min = 0", "feed_mm_per_min"),
    ("rotary_deg_per_min = 1e9", "rotary_deg_per_min"),
    ("coffee_break_min = 5", "coffee_break_min"),
])
def test_bad_times_name_the_file_and_key(tmp_path, text, key):
    f = tmp_path / "times.toml"
    f.write_text(text + "\n", encoding="utf-8")
    with pytest.raises(InputError) as err:
        read_times(f)
    assert str(f) in str(err.value) and key in str(err.value)
    assert "\n" not in str(err.value)


def test_design_times_table_names_its_key():
    with pytest.raises(InputError, match=r"c\.toml: design\.times\.tool_change_min"):
        time_model_from_table({"tool_change_min": -3}, "c.toml", "design.times")


@pytest.mark.parametrize("machine", [None, "trunnion"])
def test_the_searchs_minutes_of_a_count_vector_equal_the_schedules(machine):
    """The design search times count vectors without making runs (``Timing.total_of_counts``); it must equal the
    schedule of the runs ``designed_runs`` makes, to the last bit, from a new session and from a mounted bar."""
    from mtmcal_bayes import api
    from mtmcal_bayes.machine_time import TimeModel
    from mtmcal_bayes.planning.design_make import design_candidates
    from mtmcal_bayes.planning.design_runs import designed_runs
    from mtmcal_bayes.planning.design_timing import Timing

    c = api.campaign_of(api.demo_campaign(machine) if machine else None)
    cands = design_candidates(c)
    taken = set(c.ballbar.mounts) | {x.mount.id for x in cands}
    timing = Timing(c, TimeModel())
    rng = np.random.default_rng(0)
    last = c.ballbar.runs[-1]
    for _ in range(100):
        counts = rng.integers(0, 4, len(cands)) * (rng.random(len(cands)) < 0.1)
        for start in ((False, None, None), (True, last.setup, last.mount)):
            assert timing.total_of_counts(cands, counts, start) == timing.total(designed_runs(cands, counts, taken),
                                                                                start)


def _radius(pattern: str, R_B: float, R_C: float, L_B: float, cr_geometry: str) -> float:
    """Radius of the circle the B-axis centre runs on in the C-table frame (thesis Tables 2.2/2.3), mm."""
    if pattern in B_PATTERNS:
        return {"BR": R_B + L_B, "BT": math.hypot(R_B, L_B)}.get(pattern, R_B)
    if pattern == "CR":
        return abs(R_C - L_B) if cr_geometry == "RC-LB" else R_C + L_B
    return math.hypot(R_C, L_B) if pattern == "CT" else R_C


@pytest.mark.parametrize("rotary", [360.0, 36_000.0])  # the default; so fast that the path sets every run's time
@pytest.mark.parametrize("cr_geometry", ["RC-LB", "RC+LB"])
def test_the_clock_times_the_thesis_runs_as_tables_2_2_and_2_3(cr_geometry, rotary):
    """The one machine clock (the engine's commands over a run's motion) on the thesis campaign's planning kit: every
    run of the campaign and every pattern at both set-ups and both placements is timed as the thesis' program moves,
    ``dwell + repeats × directions × max(P / feed, span / rotary)`` with P the polygon of 720 equal chords on the
    circle of Tables 2.2/2.3 over the pattern's range, ``720 · 2r · sin(span / 1440)`` (exact, not approximated)."""
    import copy

    from mtmcal_bayes import api
    from mtmcal_bayes.planning.machine_kit import kit_of

    c = copy.deepcopy(api.campaign_of(None))
    c.ballbar.cr_geometry = cr_geometry
    bb, model = c.ballbar, TimeModel(rotary_deg_per_min=rotary)
    clock = kit_of(c).clock(model, c)
    n = TIMED_POINTS - 1
    runs = [R(r.pattern, bb.setups[r.setup], bb.mounts[r.mount], len(next(iter(r.repeats.values()))))
            for r in bb.runs]
    runs += [R(p, s, m, 2) for p in PATTERNS for s in bb.setups.values() for m in bb.mounts.values()]
    assert len(runs) > 2 * len(PATTERNS) * 2
    for r in runs:
        span = 90.0 if r.pattern in B_PATTERNS else 360.0
        P = n * 2 * _radius(r.pattern, r.setup.R_B, 0.0 if r.pattern in B_PATTERNS else r.mount.R_C, bb.length,
                            cr_geometry) * math.sin(math.radians(span) / (2 * n))
        expected = model.dwell_min + r.repeats * model.directions * max(P / bb.feed_mm_per_min,
                                                                        span / model.rotary_deg_per_min)
        assert clock.run_minutes(r) == pytest.approx(expected, rel=1e-12, abs=0), (r.pattern, r.setup.id, r.mount.id)
