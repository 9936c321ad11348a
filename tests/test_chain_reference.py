"""The chain that simulates the demo and controller-cycle campaigns and infers them, against kinematics written
out by hand from each built-in type's description file (tests/handchain.py): tool point and W ball at a few
commands, nominal and with every location error of the rotary axes and the spindle and the squareness of the linear
axes at once (on the thesis machine, whose squareness has the rigid form, tests/test_chain.py holds that form to
Eq 2.10 and it is left out here)."""

from __future__ import annotations

import numpy as np
import pytest

from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, builtin_description
from mtmcal_bayes.machines.chain import Chain
from mtmcal_bayes.machines.deviations import generated

from .handchain import SQUARENESS, HandMachine, body_of

#: position errors (mm) and orientation errors (rad, about 100″) of the check: large enough that a wrong order
#: of two bodies, a wrong sign or a wrong pivot moves the points by microns
POSITION_MM, ORIENTATION_RAD = 0.05, 5e-4


def _commands(hand: HandMachine, rng, k: int) -> dict:
    """``k`` poses: every rotary axis within ±120°, every linear axis within ±300 mm."""
    q = {}
    for letter in hand.work + hand.tool:
        span = np.deg2rad(120.0) if hand.rotary(letter) else 300.0
        q[letter] = rng.uniform(-span, span, k)
    return q


@pytest.mark.parametrize("machine", list(BUILTIN_TYPES))
@pytest.mark.parametrize("with_errors", [False, True], ids=["nominal", "location-errors"])
def test_chain_is_the_hand_written_kinematics(machine, with_errors):
    """Five poses, three tool-side points (the tool ball at two programmed lengths and a point off the spindle
    axis) and three workpiece-side points: the chain's positions equal the hand-written ones to 1e-9 mm, and a
    point the chain places on the workpiece side (``work_frame``, how a W ball or a sphere is placed) is taken
    back by the hand-written workpiece side to where it was."""
    desc = builtin_description(machine)
    hand = HandMachine(machine)
    rng = np.random.default_rng(sum(map(ord, machine)))
    motion_form = hand.squareness == "motion"  # the thesis machine's rigid form: tests/test_chain.py
    deviations = [d for d in generated(desc) if d.role != "squareness" or motion_form] if with_errors else []
    values = {}
    for d in deviations:
        if d.role == "squareness":
            letter, about = SQUARENESS[d.symbol]
            assert (d.body, d.component) == (letter, about), d.symbol
            values[d.name] = np.array([rng.choice([-1.0, 1.0]) * ORIENTATION_RAD])
            hand.tilts.setdefault(letter, np.zeros(3))[about] += values[d.name][0]
            continue
        body, role, comp = body_of(d.symbol, hand)
        assert (body, role, comp) == (d.body, d.role, d.component), d.symbol  # the symbol says what it moves
        v = rng.choice([-1.0, 1.0]) * (POSITION_MM if role == "position" else ORIENTATION_RAD) * rng.uniform(0.5, 1)
        values[d.name] = np.array([v])
        eps, delta = hand.errors.setdefault(body, (np.zeros(3), np.zeros(3)))
        target = delta if role == "position" else eps
        target += v * hand.error_axis(d.symbol)
    assert not with_errors or len(hand.errors) >= 2  # errors on at least one rotary axis and the spindle
    chain = Chain(desc, deviations)
    q = _commands(hand, rng, 5)
    tool = np.array([hand.tool_home(150.0), hand.tool_home(250.0), hand.tool_home(80.0) + [3.0, -7.0, 11.0]])
    work = np.array([[0.0, 60.0, 30.0], [120.0, -40.0, -250.0], [-35.0, 0.0, 400.0]])
    for i, (t, w) in enumerate(zip(tool, work)):
        got_t = chain.tool_point(np.broadcast_to(t, (1, 5, 3)), q, values)[0]
        got_w = chain.work_point(np.broadcast_to(w, (1, 5, 3)), q, values)[0]
        want_t = np.array([hand.tool_point(t, {a: v[j] for a, v in q.items()}) for j in range(5)])
        want_w = np.array([hand.work_point(w, {a: v[j] for a, v in q.items()}) for j in range(5)])
        assert np.max(np.abs(got_t - want_t)) < 1e-9, (i, got_t - want_t)
        assert np.max(np.abs(got_w - want_w)) < 1e-9, (i, got_w - want_w)
        # where a ball is placed on the dummy sphere (work_frame): the hand-written work side takes it back there
        placed = chain.work_frame(got_t[None], q, values)[0]
        back = np.array([hand.work_point(placed[j], {a: v[j] for a, v in q.items()}) for j in range(5)])
        assert np.max(np.abs(back - got_t)) < 1e-9, (i, back - got_t)
    if with_errors:  # the errors matter: the nominal chain is microns away
        nominal = chain.tool_point(np.broadcast_to(tool[0], (1, 5, 3)), q, {})[0] - \
            chain.work_point(np.broadcast_to(work[0], (1, 5, 3)), q, {})[0]
        actual = chain.tool_point(np.broadcast_to(tool[0], (1, 5, 3)), q, values)[0] - \
            chain.work_point(np.broadcast_to(work[0], (1, 5, 3)), q, values)[0]
        assert np.max(np.abs(actual - nominal)) > 0.01


def test_the_hand_written_rotations_turn_the_right_way():
    """The reference's own convention, by hand: +90° about +Z takes X to Y, about +X takes Y to Z, about +Y takes
    Z to X; about −Z it takes X to −Y."""
    from .handchain import rot_x, rot_y, rot_z, rodrigues

    np.testing.assert_allclose(rot_z(np.pi / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(rot_x(np.pi / 2) @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(rot_y(np.pi / 2) @ [0, 0, 1], [1, 0, 0], atol=1e-15)
    hand = HandMachine("trunnion")
    hand.axes = {**hand.axes, "C": {**hand.axes["C"], "direction": "-Z", "point_mm": [0.0, 0.0, 0.0]}}
    np.testing.assert_allclose(hand.motion("C", np.pi / 2, np.array([1.0, 0.0, 0.0]), work=True), [0, -1, 0],
                               atol=1e-15)
    for axis, R in (([1, 0, 0], rot_x), ([0, 1, 0], rot_y), ([0, 0, 1], rot_z)):
        np.testing.assert_allclose(rodrigues(0.3 * np.array(axis, float)), R(0.3), atol=1e-15)
