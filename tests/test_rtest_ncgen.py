"""The R-test run's program (``ncgen --rtest``, SPEC §22 "Program", docs/rtest.md): its blocks read back are the
R-test model's commands on every built-in type, and the commands of a run are checked against the nest centre put
on the sphere through the nominal kinematics written out by hand (tests/handchain.py, read from the description
files with tomllib: none of the package's chain code); its refusals are one line naming the key."""

from __future__ import annotations

import numpy as np
import pytest

from mtmcal_bayes.io.campaign_reader import parse_campaign
from mtmcal_bayes.io.chain_programs import campaign_program
from mtmcal_bayes.io.gcode import parse_program
from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, builtin_description
from mtmcal_bayes.io.nc_axes import DECIMALS
from mtmcal_bayes.models.rtest import RTestLayout

from .handchain import HandMachine
from .test_rtest import _recovery_runs, campaign_text

NESTS = {"N1": (150.0, False), "N2": (250.0, True)}
#: half the last printed decimal of an axis word: how far a word may be from the value it prints
PRINTED = 0.5 * 10.0 ** -DECIMALS + 1e-12


def _within(machine: str, fraction: float, k: int = 5) -> dict:
    """Each rotary axis of ``machine``: ``k`` angles over ``fraction`` of its travel (±90° where it has none),
    degrees."""
    out = {}
    for ax in builtin_description(machine).rotary_axes:
        lo, hi = np.rad2deg(ax.travel) if ax.travel is not None else (-90.0, 90.0)
        mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo) * fraction
        out[ax.letter] = np.linspace(mid - half, mid + half, k)
    return out


def _runs(machine: str) -> list[dict]:
    """Each rotary axis swept alone within its travel (the other at its travel's middle), then both together, on two
    spheres and nests, both frames and zeros."""
    (a1, s1), (a2, s2) = _within(machine, 0.8).items()
    m1, m2 = s1[2], s2[2]
    return [
        {"id": "r1", "nest": "N1", "sphere": [120.0, 40.0, 80.0], "frame": "tool", "zero": "first",
         "angles": {a1: s1, a2: [m2] * 5}},
        {"id": "r2", "nest": "N1", "sphere": [120.0, 40.0, 80.0], "frame": "machine", "zero": "absolute",
         "angles": {a1: [m1] * 5, a2: s2}},
        {"id": "r3", "nest": "N2", "sphere": [-80.0, 90.0, 150.0], "frame": "tool", "zero": "absolute",
         "angles": {a1: s1, a2: _within(machine, 0.5)[a2]}},
    ]


def _campaign(machine: str, path=None, runs=None):
    text = campaign_text(machine, runs or _runs(machine), nests=NESTS)
    if path is not None:
        path.write_text(text, encoding="utf-8")
    return parse_campaign(text)


def _reading_blocks(text: str, rotary) -> np.ndarray:
    """The positions (k, 3 + r) of the program's G01 blocks (the positions read), mm and degrees, through the
    compensation's G-code reader."""
    program = parse_program(text, rotary=tuple(rotary))
    rows = [b.position for b in program.motion if any(w.letter == "G" and w.value == 1.0 for w in b.words)]
    return np.array(rows, dtype=float)


@pytest.mark.parametrize("machine", list(BUILTIN_TYPES))
def test_each_rtest_program_reads_back_as_the_models_commands(machine):
    """Every run's program, parsed back with the machine's rotary letters: one G01 block per position, a dwell after
    each, equal to the R-test layout's commands (the linear axes through the nominal inverse chain, the rotary axes
    at the run's angles) to the printed decimals; the backed-off blocks move only along the spindle."""
    c = _campaign(machine)
    layout = RTestLayout(c)
    rotary = sorted(layout.angles)
    for run, rows in zip(c.rtest.runs, layout.slices):
        text = campaign_program(c, rtest=run.id)
        got = _reading_blocks(text, rotary)
        want = np.column_stack([layout.linear[a][rows] for a in "XYZ"]
                               + [np.rad2deg(layout.angles[a][rows]) for a in rotary])
        assert got.shape == want.shape == (run.positions, 3 + len(rotary))
        assert np.max(np.abs(got - want)) <= PRINTED, np.max(np.abs(got - want))
        assert text.count("\nG04 P2000 ") == run.positions and ("zero the sensors" in text) == (run.zero == "first")
        moves = parse_program(text, rotary=tuple(rotary)).positions()
        backed = moves[[0, -1], :3] - moves[[1, -2], :3]
        assert np.allclose(np.linalg.norm(backed, axis=1), 50.0, atol=1e-3)
        assert np.allclose(moves[[0, -1], 3:], moves[[1, -2], 3:])


def _hand_commands(hand: HandMachine, sphere, nest, q_rot: dict) -> np.ndarray:
    """X, Y, Z (3,) mm that put the nominal nest centre ``nest`` on the nominal sphere centre ``sphere`` through the
    hand-written nominal machine: the gap W(q) − T(q) is affine in the linear commands (the linear axes sit below
    every rotary axis), solved from its value at 0 and at each unit command."""
    def gap(lin):
        q = {**q_rot, **dict(zip("XYZ", lin))}
        return hand.work_point(sphere, q) - hand.tool_point(nest, q)

    g0 = gap(np.zeros(3))
    return np.linalg.solve(np.stack([gap(e) - g0 for e in np.eye(3)], axis=-1), -g0)


@pytest.mark.parametrize("machine", list(BUILTIN_TYPES))
def test_the_commands_put_the_nest_on_the_sphere_through_the_hand_written_chain(machine):
    """The program of a run that moves every rotary axis (r3: both swept) commands, at
    every position, the X, Y, Z that put the nest centre on the sphere through the nominal kinematics written out by
    hand, to the printed decimals; the commands move by tens of mm between positions (the check can fail)."""
    c = _campaign(machine)
    run = c.rtest.runs[2]
    hand = HandMachine(machine)
    rotary = sorted(run.angles)
    got = _reading_blocks(campaign_program(c, rtest="3"), rotary)
    nest = hand.tool_home(NESTS[run.nest][0])
    want = np.array([_hand_commands(hand, np.asarray(run.sphere), nest,
                                    {a: np.deg2rad(got[j, 3 + i]) for i, a in enumerate(rotary)})
                     for j in range(run.positions)])
    assert np.max(np.abs(got[:, :3] - want)) <= PRINTED, np.max(np.abs(got[:, :3] - want))
    assert np.ptp(want, axis=0).max() > 10.0


def test_the_cli_writes_an_rtest_program_and_refuses_in_one_line(run_cli, tmp_path):
    """``ncgen --rtest RUN CAMPAIGN -o FILE`` writes the program (its dwell as asked); a campaign without R-test runs,
    an unknown run, a dwell that is not a positive whole number of ms, a dwell without an R-test run and a ball-bar
    option with one, a run beyond a rotary axis' travel: exit 2, one line naming the key or flag, nothing written."""
    path, beyond = tmp_path / "c.toml", tmp_path / "beyond.toml"
    _campaign("trunnion", path)
    _campaign("trunnion", beyond, _recovery_runs("trunnion"))  # A from -90 to 90 deg: beyond its travel
    out = tmp_path / "r.nc"
    code, text, err = run_cli("ncgen", "--rtest", "r2", path, "--dwell-ms", "750", "-o", out)
    assert code == 0 and text == "", err
    program = out.read_text()
    assert program.count("\nG04 P750 ") == 5 and program.rstrip().endswith("M30")
    assert "Fanuc-type" in program and "axis letters" in program and "NC frame" in program
    out.unlink()
    for argv, key in ((["--rtest", "1", "--machine", "trunnion"], "trunnion-demo.toml: rtest.runs: "),
                      (["--rtest", "r9", path], "--rtest: no R-test run 'r9'"),
                      (["--rtest", "5", path], "--rtest: no R-test run '5'"),
                      (["--rtest", "1", path, "--dwell-ms", "0"], "--dwell-ms: must be a positive whole number"),
                      (["--probe", "1", "--machine", "trunnion", "--dwell-ms", "10"], "--dwell-ms: only with an R-test"),
                      (["--rtest", "1", path, "--step-deg", "5"], "--step-deg: an option of a ball-bar program"),
                      (["--rtest", "1", beyond], "--rtest: A reaches -90..90 deg, beyond its travel [-120, 30] deg")):
        code, text, err = run_cli("ncgen", *argv, "-o", out)
        assert code == 2 and text == "" and len(err.strip().splitlines()) == 1 and key in err, (argv, err)
        assert "Traceback" not in err and not out.exists()
