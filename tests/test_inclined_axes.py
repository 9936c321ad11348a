"""Inclined rotary axes (SPEC §21, issue 43): the basis rule and names of an inclined axis and of the spindle it
carries; a frame-aligned axis taken through the inclined path (forced) gives today's ball-bar and probe predictions
after the documented change of names; a nutating head against kinematics written here without the package's model
code (each rotary axis a Rodrigues rotation about its actual line)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.errors import InputError
from mtmcal_bayes.io.machine_reader import demo_campaign, parse_description
from mtmcal_bayes.machines.chain import Chain
from mtmcal_bayes.machines.description import inclined_basis
from mtmcal_bayes.machines.deviations import generated
from mtmcal_bayes.machines.patterns import pattern_commands, placement_commands
from mtmcal_bayes.machines.selection import selected
from mtmcal_bayes.machines.space import described_space
from mtmcal_bayes.models.ballbar import BallbarModel, ChainKernel
from mtmcal_bayes.models.probe import ChainProbeKernel, ProbeLayout, ProbeModel

S = 0.70710678  # the nutating head's direction as a user writes it: [0, S, S], 3e-9 short of unit length
ARCSEC = np.pi / 180.0 / 3600.0


# ------------------------------------------------------------------------------------------------ the basis rule

@pytest.mark.parametrize("k, u, v", [
    ([0, 1, 0], [1, 0, 0], [0, 0, -1]),      # §21's example: +Y -> u = +X, v = −Z
    ([0, -1, 0], [1, 0, 0], [0, 0, 1]),
    ([1, 0, 0], [0, 1, 0], [0, 0, 1]),       # ties Y, Z: Y first
    ([-1, 0, 0], [0, 1, 0], [0, 0, -1]),
    ([0, 0, 1], [1, 0, 0], [0, 1, 0]),       # ties X, Y: X first
    ([0, 0, -1], [1, 0, 0], [0, -1, 0]),
    ([0, S, S], [1, 0, 0], [0, S, -S]),      # the nutating head: X is across it
    ([0.6, 0.0, 0.8], [0, 1, 0], [-0.8, 0, 0.6]),
    ([0.36, 0.48, 0.8], None, None),        # a general direction: X has the smallest component
])
def test_the_basis_is_the_nearest_perpendicular_frame_axis_projected(k, u, v):
    """u: the frame axis with the smallest |eᵢ·k| projected across k and normalised (ties X, Y, Z in that order);
    v = k × u; the three right-handed and orthonormal."""
    k = np.asarray(k, float) / np.linalg.norm(k)
    bu, bv = inclined_basis(k)
    if v is not None:
        np.testing.assert_allclose(bu, u, atol=1e-8)
        np.testing.assert_allclose(bv, np.asarray(v, float) / np.linalg.norm(v), atol=1e-8)
    else:  # X is the smallest component: u along X less its part along k
        want = np.array([1.0, 0, 0]) - k[0] * k
        np.testing.assert_allclose(bu, want / np.linalg.norm(want), atol=1e-12)
    frame = np.array([bu, bv, k])
    np.testing.assert_allclose(frame @ frame.T, np.eye(3), atol=1e-12)
    assert np.linalg.det(frame) == pytest.approx(1.0, abs=1e-12)


def nutating_table(b_point=(0.0, 0.0, 150.0), spindle="-Z", **extra) -> dict:
    """A nutating head written here: a C table (+Z through the origin), a B head on the tool side whose axis is
    [0, S, S] through ``b_point`` (mm), carrying the spindle along ``spindle`` at B = 0 from the origin."""
    return {"configuration": "w-C'bZYXB(C1)-t",
            "axes": {"C": {"direction": "+Z", "point_mm": [0.0, 0.0, 0.0]},
                     "B": {"direction": [0.0, S, S], "point_mm": list(b_point), "travel_deg": [-180.0, 180.0]}},
            "spindle": {"direction": spindle, "point_mm": [0.0, 0.0, 0.0]}} | extra


def nutating(**kw):
    return parse_description(nutating_table(**kw), "<test nutating head>", "")


def test_an_inclined_axis_and_its_spindle_are_named_by_their_bases():
    """The B head's five errors are E_U0B, E_V0B, E_RU0B, E_RV0B, E_B0B along/about u = +X, v = [0, S, −S], k; the
    spindle (−Z) carried by it has u = the projection of k across −Z = +Y and v = s × u = +X, both frame axes, so
    it keeps §19's frame names; a spindle along [S, 0, −S] has neither in the frame and gets E_U(0C1)B, ..., its
    offset E_W(0C1)B signed along s.  The default selection (SPEC §21's computed rule) keeps the inclined axis' zero
    and orientations; its positions act only with the C axis' (E_U0B as −E_X0C, E_V0B as −S·E_Y0C and a sphere's
    placement) and are left out (tests/test_default_selection.py)."""
    desc = nutating()
    b = desc.axes["B"]
    assert b.inclined and not desc.axes["C"].inclined
    np.testing.assert_allclose(b.direction, [0, np.sqrt(0.5), np.sqrt(0.5)], atol=1e-15)
    errs = {d.symbol: d for d in generated(desc)}
    on_b = [d.symbol for d in generated(desc) if d.body == "B"]
    assert on_b == ["E_U0B", "E_V0B", "E_RU0B", "E_RV0B", "E_B0B"]
    k = b.direction
    for sym, want in (("E_U0B", [1, 0, 0]), ("E_V0B", np.cross(k, [1, 0, 0])), ("E_RU0B", [1, 0, 0]),
                      ("E_RV0B", np.cross(k, [1, 0, 0])), ("E_B0B", k)):
        np.testing.assert_allclose(errs[sym].vector, want, atol=1e-15)
        assert errs[sym].component is None
    assert [errs[s].kind for s in on_b] == ["length", "length", "angle", "angle", "angle"]
    assert [d.symbol for d in generated(desc) if d.body == "C1"] == \
        ["E_X(0C1)B", "E_Y(0C1)B", "E_A(0C1)B", "E_B(0C1)B", "E_Z(0C1)B"]
    chosen = [d.symbol for d in selected(desc)]
    assert set(on_b) & set(chosen) == {"E_RU0B", "E_RV0B", "E_B0B"}

    tilted = nutating(spindle=[S, 0.0, -S])
    names = [d.symbol for d in generated(tilted) if d.body == "C1"]
    assert names == ["E_U(0C1)B", "E_V(0C1)B", "E_RU(0C1)B", "E_RV(0C1)B", "E_W(0C1)B"]
    w = {d.symbol: d for d in generated(tilted)}["E_W(0C1)B"]
    np.testing.assert_allclose(w.vector, tilted.spindle.direction, atol=1e-15)


@pytest.mark.parametrize("direction, words", [
    ([0.0, 0.0, 0.0], "a zero vector has no direction"),
    ([0.0, S, S + 1e-3], "is not a unit vector (its length is 1.0007"),
])
def test_a_zero_or_non_unit_inclined_direction_is_one_line_naming_the_key(direction, words):
    table = nutating_table()
    table["axes"]["B"]["direction"] = direction
    with pytest.raises(InputError) as info:
        parse_description(table, "m.toml", "machine")
    assert info.value.key == "machine.axes.B.direction" and words in info.value.message, str(info.value)
    assert "\n" not in str(info.value)


# ------------------------------------------------------------------ a frame-aligned axis through the inclined path

#: the §21 table: per direction of a frame-aligned axis K, its inclined-path errors as ± its frame-named ones
#: (U, V, RU, RV, K0K) -> (sign, frame letter of the position / orientation); the zero turns about k itself
FRAME_TABLE = {
    "+X": [(1, "Y"), (1, "Z"), (1, "B"), (1, "C"), (1, None)],
    "+Y": [(1, "X"), (-1, "Z"), (1, "A"), (-1, "C"), (1, None)],
    "+Z": [(1, "X"), (1, "Y"), (1, "A"), (1, "B"), (1, None)],
    "-X": [(1, "Y"), (-1, "Z"), (1, "B"), (-1, "C"), (-1, None)],
    "-Y": [(1, "X"), (1, "Z"), (1, "A"), (1, "C"), (-1, None)],
    "-Z": [(1, "X"), (-1, "Y"), (1, "A"), (-1, "B"), (-1, None)],
}
ZERO_OF = {"X": "A", "Y": "B", "Z": "C"}


def _sign_name(direction: np.ndarray) -> str:
    i = int(np.argmax(np.abs(direction)))
    return ("+" if direction[i] > 0 else "-") + "XYZ"[i]


def forced(desc, letters):
    """``desc`` with its rotary axes ``letters`` taken through the inclined path (the tests' flag)."""
    def swap(chain):
        return tuple(dataclasses.replace(a, force_inclined=True) if a.letter in letters else a for a in chain)
    return dataclasses.replace(desc, work_chain=swap(desc.work_chain), tool_chain=swap(desc.tool_chain))


def renamed(desc, letters, values: dict) -> dict:
    """Frame-named deviation values ``{symbol: (n,)}`` as the inclined path of ``letters`` names them (FRAME_TABLE)."""
    out = dict(values)
    for K in letters:
        direction = _sign_name(desc.axes[K].direction)
        zero = f"E_{ZERO_OF[direction[1]]}0{K}"
        for (sign, letter), b in zip(FRAME_TABLE[direction], ("U", "V", "RU", "RV", "K")):
            frame = zero if letter is None else f"E_{letter}0{K}"
            out.pop(frame)
            out[f"E_{K}0{K}" if b == "K" else f"E_{b}0{K}"] = sign * values[frame]
    return out


@pytest.mark.parametrize("direction", list(FRAME_TABLE))
def test_the_forced_path_names_a_frame_axis_by_the_table(direction):
    """The inclined path's vector of each error of a frame-aligned axis is FRAME_TABLE's sign times the frame-named
    error's vector: the table the docs give is the code's."""
    desc = parse_description(nutating_table(), "<t>", "")
    b = dataclasses.replace(desc.axes["B"], direction=_unit(direction), point=np.array([0.0, 0.0, 150.0]))
    frame = dataclasses.replace(desc, tool_chain=desc.tool_chain[:-1] + (b,))
    vec = {d.symbol: d.vector for d in generated(frame) if d.body == "B"}
    incl = {d.symbol: d.vector for d in generated(forced(frame, "B")) if d.body == "B"}
    zero = f"E_{ZERO_OF[direction[1]]}0B"
    for (sign, letter), b in zip(FRAME_TABLE[direction], ("U", "V", "RU", "RV", "K")):
        name = "E_B0B" if b == "K" else f"E_{b}0B"
        np.testing.assert_array_equal(incl[name], sign * vec[zero if letter is None else f"E_{letter}0B"])


def _unit(direction: str) -> np.ndarray:
    v = np.zeros(3)
    v["XYZ".index(direction[1])] = 1.0 if direction[0] == "+" else -1.0
    return v


def _random_values(desc, rng, n: int) -> dict:
    """``{symbol: (n,)}`` internal units: every location error of the rotary axes and the spindle, ±20–50 µm and
    ±20–100″ (large enough that a wrong sign or axis moves a reading by microns)."""
    out = {}
    for d in generated(desc):
        if d.role == "squareness":
            continue
        size = 0.05 if d.kind == "length" else 100 * ARCSEC
        out[d.symbol] = rng.choice([-1.0, 1.0], n) * size * rng.uniform(0.4, 1.0, n)
    return out


@pytest.mark.parametrize("machine, letters", [("vertical-turn-mill", "B"), ("vertical-turn-mill", "BC"),
                                              ("trunnion", "AC"), ("head-head", "CA")])
def test_a_frame_axis_through_the_inclined_path_predicts_as_today(machine, letters):
    """The demo campaign's ball-bar lengths at every point (placements and runs) and probe readings at every
    position, for a batch of 4 random deviation sets, through the frame path and through the inclined path with
    the same values renamed by FRAME_TABLE: the deviations' effects (actual minus nominal) agree to 1e-9 relative
    (B +Y, A +X, C +Z on the demos)."""
    c = mb.load_campaign(demo_campaign(machine))
    desc = c.machine.description
    inc = forced(desc, letters)
    assert all(inc.axes[K].inclined for K in letters) and not any(desc.axes[K].inclined for K in letters)
    values = _random_values(desc, np.random.default_rng(len(machine) + len(letters)), 4)
    other = renamed(desc, letters, values)
    assert set(other) == {d.symbol for d in generated(inc) if d.role != "squareness"}

    pts = BallbarModel(c).points()
    zeros = {b: np.zeros((4, len(pts.length))) for b in ("xT", "yT", "zT", "dRB")}
    w_off = np.zeros((4, len(pts.length), 3))
    frame_k, inc_k = ChainKernel(desc), ChainKernel(inc)
    nominal = frame_k.lengths(pts, {}, zeros, w_off)
    a = frame_k.lengths(pts, values, zeros, w_off) - nominal
    b = inc_k.lengths(pts, other, zeros, w_off) - inc_k.lengths(pts, {}, zeros, w_off)
    assert np.max(np.abs(a)) > 1e-3  # the deviations move the bar by microns
    assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(a)), np.max(np.abs(a - b))

    kernel_f, kernel_i = ChainProbeKernel(desc), ChainProbeKernel(inc)
    layout = ProbeLayout(c, kernel=kernel_f)
    k = len(layout.length)
    terms = {t: np.zeros((4, k)) for t in (*kernel_f.terms, "xP", "yP", "zP")}
    base = kernel_f.readings(layout, {}, terms, 4)
    ra = kernel_f.readings(layout, values, terms, 4) - base
    rb = kernel_i.readings(layout, other, terms, 4) - kernel_i.readings(layout, {}, terms, 4)
    assert np.max(np.abs(ra)) > 1e-3
    assert np.max(np.abs(ra - rb)) <= 1e-9 * np.max(np.abs(ra)), np.max(np.abs(ra - rb))


# ------------------------------------------------------------- a nutating head against kinematics written here

def rodrigues(v: np.ndarray, k: np.ndarray, p: np.ndarray, angle: float) -> np.ndarray:
    """``v`` (3,) turned by ``angle`` right-handedly about the line through ``p`` along unit ``k``."""
    r = v - p
    return p + r * np.cos(angle) + np.cross(k, r) * np.sin(angle) + k * (k @ r) * (1.0 - np.cos(angle))


def small_turn(v: np.ndarray, w: np.ndarray, p: np.ndarray) -> np.ndarray:
    """``v`` (3,) turned about the line through ``p`` by the rotation vector ``w`` (3,) rad (its angle |w|)."""
    angle = float(np.linalg.norm(w))
    return rodrigues(v, w / angle, p, angle) if angle > 0 else v


class HandNutating:
    """The nutating head of :func:`nutating_table` written out without the package's model code.

    Each error as §19 and §21 define it: a small rigid displacement, at the home pose, of the body its axis carries:
    the orientation errors and the zero one small rotation through the axis' point (rotation vector: for B
    ``E_RU0B·u + E_RV0B·v + E_B0B·k``, for C ``E_A0C·X + E_B0C·Y + E_C0C·Z``, for the spindle ``E_A(0C1)B·X +
    E_B(0C1)B·Y`` through its point), then the positions (B: along u, v; C: X, Y; the spindle: X, Y, Z).  An axis
    then turns what it carries by its command about its *actual* line, the nominal line displaced the same way
    (a Rodrigues rotation about that line); the spindle's displacement is carried by B, B's line by the linear axes."""

    def __init__(self, e: dict, b_point=(0.0, 0.0, 150.0), spindle_point=(0.0, 0.0, 0.0)):
        """``e`` every location error by symbol (mm, rad; absent: 0); ``b_point`` B's point, ``spindle_point`` the
        spindle's (mm; the built-in ``nutating-head`` type: (0, 0, 440) and (0, 0, 300))."""
        e = {n: e.get(n, 0.0) for n in NUTATING_ERRORS}
        self.e = e
        k = np.array([0.0, S, S]) / np.linalg.norm([0.0, S, S])
        u = np.array([1.0, 0.0, 0.0])
        self.b = (k, np.array(b_point, float), e["E_RU0B"] * u + e["E_RV0B"] * np.cross(k, u) + e["E_B0B"] * k,
                  e["E_U0B"] * u + e["E_V0B"] * np.cross(k, u))
        z = np.array([0.0, 0.0, 1.0])
        self.c = (z, np.zeros(3), np.array([e["E_A0C"], e["E_B0C"], e["E_C0C"]]),
                  np.array([e["E_X0C"], e["E_Y0C"], 0.0]))
        self.spindle = (np.array(spindle_point, float), np.array([e["E_A(0C1)B"], e["E_B(0C1)B"], 0.0]),
                        np.array([e["E_X(0C1)B"], e["E_Y(0C1)B"], e["E_Z(0C1)B"]]))

    @staticmethod
    def _axis(v: np.ndarray, axis, angle: float, inverse: bool = False) -> np.ndarray:
        """``v`` carried by a rotary axis ``(k, p, rotation vector, shift)`` at ``angle``: displaced with the
        body, then turned about the actual line (``inverse``: the way back)."""
        k0, p0, w, d = axis
        k, p = small_turn(k0, w, np.zeros(3)), p0 + d
        if inverse:
            v = rodrigues(v, k, p, -angle) - d
            return small_turn(v, -w, p0)
        return rodrigues(small_turn(v, w, p0) + d, k, p, angle)

    def tool(self, t: np.ndarray, q: dict) -> np.ndarray:
        """A tool-side point ``t`` (3,) given at the home pose, at commands ``q``."""
        p, w, d = self.spindle
        t = small_turn(t, w, p) + d
        return self._axis(t, self.b, q["B"]) + np.array([q["X"], q["Y"], q["Z"]])

    def work(self, w: np.ndarray, q: dict) -> np.ndarray:
        """A table point ``w`` (3,) (its place at the home pose) at commands ``q``."""
        return self._axis(w, self.c, q["C"])

    def work_inverse(self, x: np.ndarray, q: dict) -> np.ndarray:
        """Where a machine-frame point ``x`` sits on the table at commands ``q``, as its place at the home pose."""
        return self._axis(x, self.c, q["C"], inverse=True)


def test_a_point_on_the_actual_line_stays_put():
    """The reference itself: a point of B's actual line (the nominal line displaced with the body) carried by B
    does not move as B turns, and work_inverse undoes work."""
    rng = np.random.default_rng(3)
    e = {n: rng.normal(0, 1e-3) for n in NUTATING_ERRORS}
    hand = HandNutating(e)
    k0, p0, w, d = hand.b
    home = p0 + 37.0 * k0  # on the nominal line; displaced with the body it lies on the actual line
    at = [hand._axis(home, hand.b, b) for b in (0.0, 0.7, -2.0)]
    np.testing.assert_allclose(at[1], at[0], atol=1e-12)
    np.testing.assert_allclose(at[2], at[0], atol=1e-12)
    x, q = np.array([10.0, -20.0, 30.0]), {"C": 1.1}
    np.testing.assert_allclose(hand.work(hand.work_inverse(x, q), q), x, atol=1e-12)


#: the nutating head's location errors with their size (mm, rad)
NUTATING_ERRORS = {"E_X0C": 0.05, "E_Y0C": 0.05, "E_A0C": 100 * ARCSEC, "E_B0C": 100 * ARCSEC, "E_C0C": 100 * ARCSEC,
                   "E_U0B": 0.05, "E_V0B": 0.05, "E_RU0B": 100 * ARCSEC, "E_RV0B": 100 * ARCSEC, "E_B0B": 100 * ARCSEC,
                   "E_X(0C1)B": 0.05, "E_Y(0C1)B": 0.05, "E_A(0C1)B": 100 * ARCSEC, "E_B(0C1)B": 100 * ARCSEC,
                   "E_Z(0C1)B": 0.05}


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_nutating_head_is_the_hand_written_kinematics(seed):
    """Random small values of every location error; (a) the tool point and a table point at 6 random commands
    (B, C within ±170°, linear axes ±300 mm); (b) the ball bar's length at every point of the patterns BR, BT,
    BA, BZ, CR, CT (B held at a random angle for the C patterns), the W ball placed where the actual tool ball is at
    the placement pose: the chain equals the reference to 1e-9 mm.  The errors move the points by microns."""
    desc = nutating()
    assert set(NUTATING_ERRORS) == {d.symbol for d in generated(desc) if d.role != "squareness"}
    rng = np.random.default_rng(seed)
    e = {n: float(rng.choice([-1.0, 1.0]) * size * rng.uniform(0.3, 1.0)) for n, size in NUTATING_ERRORS.items()}
    hand = HandNutating(e)
    chain = Chain(desc, generated(desc))
    dev = {n: np.array([v]) for n, v in e.items()}

    k = 6
    q = {"B": rng.uniform(-3.0, 3.0, k), "C": rng.uniform(-3.0, 3.0, k)} | \
        {a: rng.uniform(-300.0, 300.0, k) for a in "XYZ"}
    t0, w0 = np.array([3.0, -5.0, -180.0]), np.array([40.0, -25.0, 60.0])
    got_t = chain.tool_point(np.broadcast_to(t0, (1, k, 3)), q, dev)[0]
    got_w = chain.work_point(np.broadcast_to(w0, (1, k, 3)), q, dev)[0]
    qs = [{a: v[j] for a, v in q.items()} for j in range(k)]
    want_t = np.array([hand.tool(t0, qj) for qj in qs])
    want_w = np.array([hand.work(w0, qj) for qj in qs])
    assert np.max(np.abs(got_t - want_t)) < 1e-9, got_t - want_t
    assert np.max(np.abs(got_w - want_w)) < 1e-9, got_w - want_w
    nominal_t = chain.tool_point(np.broadcast_to(t0, (1, k, 3)), q, {})[0]
    assert np.max(np.abs(got_t - nominal_t)) > 1e-2

    length, ball, bar = 180.0, np.array([60.0, 20.0, 0.0]), 100.0
    tool = desc.spindle.point + length * desc.spindle.direction
    place = placement_commands(desc, length=length, ball=ball)
    hold = float(rng.uniform(-60.0, 60.0))
    for pattern in ("BR", "BT", "BA", "BZ", "CR", "CT"):
        cmd = pattern_commands(desc, pattern, length=length, ball=ball, bar=bar,
                               arc_deg=np.linspace(-80.0, 80.0, 9), hold_deg={"B": hold} if pattern[0] == "C" else None)
        n_pts = len(cmd.psi)
        qq = {a: np.concatenate([place[a], v]) for a, v in cmd.q.items()}
        placement = np.zeros(n_pts + 1, dtype=int)
        lengths = np.full((1, n_pts + 1), length)
        got = chain.ballbar_lengths(lengths, np.zeros((1, n_pts + 1, 3)), qq, placement=placement,
                                    w_off=np.zeros((1, n_pts + 1, 3)), dev=dev)[0]
        q_place = {a: v[0] for a, v in place.items()}
        w_home = hand.work_inverse(hand.tool(tool, q_place), q_place)
        want = []
        for j in range(n_pts + 1):
            qj = {a: v[j] for a, v in qq.items()}
            want.append(np.linalg.norm(hand.tool(tool, qj) - hand.work(w_home, qj)))
        assert np.max(np.abs(got - np.array(want))) < 1e-9, (pattern, got - np.array(want))
        nominal = chain.ballbar_lengths(lengths, np.zeros((1, n_pts + 1, 3)), qq, placement=placement,
                                        w_off=np.zeros((1, n_pts + 1, 3)), dev={})[0]
        np.testing.assert_allclose(nominal[1:], bar, atol=1e-9)  # the nominal pattern keeps the bar's length
        assert np.max(np.abs(got - nominal)) > 1e-3, pattern


# ------------------------------------------------------------------------------------------------- the axes command

PROBE_CAMPAIGN = """[probe]
instrument = "touch-trigger probe"
repeatability_um = 1.0

[probe.styli.S1]
length_mm = 150.0

[[probe.runs]]
id = "sphere"
stylus = "S1"
sphere_mm = [0.0, 100.0, 0.0]
centres_mm = [{centres}]

[probe.runs.angles_deg]
B = [0.0, 60.0, 120.0, 180.0, 0.0, 60.0, 120.0, 180.0, 0.0, 90.0, -90.0, -60.0]
C = [0.0, 0.0, 0.0, 0.0, 90.0, 90.0, 90.0, 90.0, 180.0, 270.0, 180.0, 270.0]
"""


def _probe_campaign(tmp_path) -> str:
    """A probe-only campaign on the nutating head: one sphere read at 12 positions of B and C, the readings its
    nominal ones plus 1 µm scatter (seeded)."""
    from mtmcal_bayes.io.tomlio import dumps

    def write(centres: np.ndarray) -> str:
        path = tmp_path / "nutating.toml"
        rows = "[" + ", ".join("[" + ", ".join(repr(float(x)) for x in r) + "]" for r in centres) + "]"
        path.write_text('format = "mtmcal-campaign/1"\n\n' + dumps({"machine": nutating_table()}) + "\n" +
                        PROBE_CAMPAIGN.format(centres=rows), encoding="utf-8")
        return str(path)

    first = write(np.zeros((12, 3)))
    kernel = ChainProbeKernel(nutating())
    zero = kernel.zero(ProbeLayout(mb.load_campaign(first), kernel=kernel))
    return write(zero + np.random.default_rng(5).normal(0.0, 0.001, zero.shape))


def test_axes_gives_the_inclined_axis_line_and_basis_in_the_machine_frame(tmp_path, run_cli):
    """``axes`` on a campaign of the nutating head: the JSON's ``inclined`` entry gives B's nominal direction
    [0, 1, 1]/√2 through (0, 0, 150) and its basis u = +X, v = [0, 1, −1]/√2; its table's nominal direction and point
    of B are that line; the text prints the line and the basis; the C table (along +Z) has no such entry."""
    import json

    path = _probe_campaign(tmp_path)
    code, out, err = run_cli("axes", path, "--json")
    assert code == 0, err
    got = json.loads(out)
    r = np.sqrt(0.5)
    b = got["inclined"]["B"]
    assert set(got["inclined"]) == {"B"}
    np.testing.assert_allclose(b["direction"], [0.0, r, r], atol=1e-12)
    np.testing.assert_allclose(b["point_mm"], [0.0, 0.0, 150.0], atol=1e-12)
    np.testing.assert_allclose(b["u"], [1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(b["v"], [0.0, r, -r], atol=1e-12)
    nominal = {(row["element"], row["quantity"]): row["nominal"] for row in got["lines"]}
    np.testing.assert_allclose([nominal["B", f"direction_{a}"] for a in "xyz"], [0.0, r, r], atol=1e-12)
    np.testing.assert_allclose([nominal["B", f"point_{a}"] for a in "xyz"], [0.0, 0.0, 150.0], atol=1e-9)
    code, text, err = run_cli("axes", path)
    assert code == 0, err
    assert ("inclined B axis: nominal line along [0, 0.707106781, 0.707106781] through [0, 0, 150] mm; its basis "
            "u = [1, 0, 0], v = [0, 0.707106781, -0.707106781]") in text


def test_the_machine_figures_give_an_inclined_axis_by_its_vector_and_basis(tmp_path):
    """The report's machine figure names the B head's direction as its vector (not the frame axis nearest it), and the
    deviations figure gives B's line, its basis and its five errors in words (their drawing in the basis is not made
    yet) and draws the rest as before."""
    import matplotlib.text

    from mtmcal_bayes.reporting.machine_figure import figure_jobs

    c = mb.load_campaign(_probe_campaign(tmp_path))
    texts = {}
    for name, job in figure_jobs(c):
        fig = job()
        texts[name] = "\n".join(t.get_text() for t in fig.findobj(matplotlib.text.Text))
    assert "B: rotary, [0, 0.7071, 0.7071] through" in texts["machine.png"]
    assert "+Y through" not in texts["machine.png"]
    words = texts["deviations.png"]
    assert "its basis: u = [1, 0, 0], v = [0, 0.7071, -0.7071]" in words
    for sym in ("E_U0B", "E_V0B", "E_RU0B", "E_RV0B", "E_B0B"):
        assert f"{sym}: " in words


def test_a_radial_pattern_with_the_ball_on_the_inclined_line_swings_the_bar_across_it():
    """BR with the T ball on B's line: r̂ is taken as B's u (across B), so the bar stays perpendicular to B's
    direction as B turns, and the nominal bar keeps its length."""
    desc = nutating(b_point=(0.0, 0.0, 0.0))
    b = desc.axes["B"]
    # the tool ball at length 0 sits at the spindle point (0, 0, 0), on B's line through the origin
    cmd = pattern_commands(desc, "BR", length=0.0, ball=np.array([0.0, 0.0, -100.0]), bar=100.0,
                           arc_deg=np.linspace(0.0, 90.0, 5))
    chain = Chain(desc, [])
    t = chain.tool_point(np.zeros((1, 5, 3)), cmd.q, {})[0]
    w = chain.work_point(np.broadcast_to([0.0, 0.0, -100.0], (1, 5, 3)), cmd.q, {})[0]  # the W ball on the table
    bar = t - w
    np.testing.assert_allclose(np.linalg.norm(bar, axis=1), 100.0, atol=1e-9)
    np.testing.assert_allclose(bar @ b.direction, 0.0, atol=1e-9)


def test_the_docs_table_of_a_frame_aligned_axis_is_the_codes():
    """docs/machines.md's table of a frame-aligned axis in the basis: each row's u and v are the basis rule's and its
    five entries are FRAME_TABLE's (which the forced path's test holds to the code), every direction present."""
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "machines.md").read_text(encoding="utf-8")
    rows = {}
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 8 and cells[0] in {"+X", "−X", "+Y", "−Y", "+Z", "−Z"}:
            rows[cells[0].replace("−", "-")] = cells
    assert set(rows) == set(FRAME_TABLE)
    for direction, cells in rows.items():
        u, v = inclined_basis(_unit(direction))
        assert [_unit(cells[1].replace("−", "-")), _unit(cells[2].replace("−", "-"))] == [pytest.approx(u),
                                                                                        pytest.approx(v)]
        axis = "XYZ".index(direction[1])
        for (sign, letter), cell in zip(FRAME_TABLE[direction], cells[3:]):
            want = f"{'−' if sign < 0 else ''}`E_{letter or ZERO_OF['XYZ'[axis]]}0K`"
            assert cell == want, (direction, cell, want)


class _Renamed:
    """A kernel of the inclined path fed the frame names' values (the change of names of FRAME_TABLE)."""

    def __init__(self, inner, desc, letters):
        self.inner, self.desc, self.letters = inner, desc, letters
        self.name, self.complex_step = inner.name, inner.complex_step
        self.terms = getattr(inner, "terms", None)

    def _dev(self, dev: dict) -> dict:
        full = {d.symbol: dev.get(d.symbol, np.zeros(1)) for d in generated(self.desc) if d.role != "squareness"}
        return renamed(self.desc, self.letters, full) | {k: v for k, v in dev.items() if k not in full}

    def lengths(self, pts, dev, setup_terms, w_off):
        return self.inner.lengths(pts, self._dev(dev), setup_terms, w_off)

    def zero(self, layout):
        return self.inner.zero(layout)

    def readings(self, layout, dev, terms, n):
        return self.inner.readings(layout, self._dev(dev), terms, n)


@pytest.mark.parametrize("machine, letters", [("vertical-turn-mill", "BC"), ("trunnion", "AC")])
def test_the_models_predict_a_batch_alike_through_both_paths(machine, letters):
    """The ball-bar model's eccentricities and the probe model's readings of the demo campaign for a batch of 8
    parameter vectors ``(n, p)`` (every location error of the rotary axes and the spindle, ±50 µm / ±100″, and the
    nuisance terms, sd 10 µm): the models through the inclined path (the values renamed by FRAME_TABLE) predict
    what the frame path predicts, to 1e-9 of the largest prediction."""
    c = mb.load_campaign(demo_campaign(machine))
    desc = c.machine.description
    inc = forced(desc, letters)
    names = [d.name for d in generated(desc) if d.role != "squareness"]
    rng = np.random.default_rng(7)
    for data, model in (("ballbar", BallbarModel), ("probe", ProbeModel)):
        space = described_space(c, names, data=data)
        theta = np.array([[rng.choice([-1.0, 1.0]) * rng.uniform(0.4, 1.0) *
                           ((0.05 if p.kind == "length" else 100 * ARCSEC) if p.group == "deviation" else 0.01)
                           for p in space.parameters] for _ in range(8)])
        kernel = ChainKernel if data == "ballbar" else ChainProbeKernel
        frame = model(c, space)
        other = model(c, space, kernel=_Renamed(kernel(inc), desc, letters))
        a, b = frame.predict(theta), other.predict(theta)
        assert a.shape == (8, len(frame.observations)) and np.max(np.abs(a)) > 1e-3
        assert np.max(np.abs(a - b)) <= 1e-9 * np.max(np.abs(a)), (data, np.max(np.abs(a - b)))
