"""The R-test (SPEC §22, docs/rtest.md): its format, its model against kinematics written out by hand, its relation
to the touch probe, its bad inputs, and its posterior against a stated truth on every built-in type.

The reference (:func:`reference_readings`) uses none of the package's model code: the hand-written machine of
tests/handchain.py (each axis a rotation about its actual line, each linear axis a translation, each body's location
errors a rigid displacement outside its own motion), the nominal inverse solved here from the nominal hand-written
machine (the chain is affine in the linear commands), the sensors' axes as the product of the spindle body's rotations
written out here, and the displacement taken in the nest frame."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mtmcal_bayes
from mtmcal_bayes import api
from mtmcal_bayes.errors import InputError
from mtmcal_bayes.inference.identifiability import DETERMINED
from mtmcal_bayes.inference.log_posterior import parameter_space
from mtmcal_bayes.io.campaign_reader import load_campaign, parse_campaign
from mtmcal_bayes.io.campaign_writer import save_campaign
from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, THESIS_TYPE, builtin_description
from mtmcal_bayes.machines.deviations import generated, quantities
from mtmcal_bayes.machines.space import described_space
from mtmcal_bayes.models import make_model
from mtmcal_bayes.models.probe import ProbeModel
from mtmcal_bayes.models.rtest import RTestModel
from mtmcal_bayes.simulation.simulate import synthetic_campaign

from .handchain import SQUARENESS, HandMachine, body_of, rodrigues
from .rtest_campaigns import _toml_list, campaign_text

#: the machines' errors of the reference check: large enough that a wrong sign, order or pivot moves a reading by
#: microns (mm, rad: about 100″)
POSITION_MM, ORIENTATION_RAD = 0.05, 5e-4
#: the nuisance terms' sizes in the reference check, mm
TERM_MM = {"xZR": 0.02, "yZR": 0.02, "zZR": 0.02, "xPR": 0.05, "yPR": 0.05, "zPR": 0.05, "xNR": 0.01,
           "yNR": 0.01, "zNR": 0.01, "dLR": 0.01}


def _rotary(machine: str) -> list[str]:
    return [a.letter for a in builtin_description(machine).rotary_axes]


def _reference_runs(machine: str, frame: str, zero: str, rng) -> list[dict]:
    """Two runs at random positions of every rotary axis: the one under test, and one of the other frame and zero
    on another sphere and nest (so that owners and the frame switch are exercised in one batch)."""
    axes = _rotary(machine)
    other = {"frame": "machine" if frame == "tool" else "tool", "zero": "absolute" if zero == "first" else "first"}
    return [{"id": "r1", "nest": "N1", "sphere": [110.0, -35.0, 60.0], "frame": frame, "zero": zero,
             "angles": {a: rng.uniform(-120, 120, 5) for a in axes}},
            {"id": "r2", "nest": "N2", "sphere": [-70.0, 80.0, 140.0], "placement": "S2", **other,
             "angles": {a: rng.uniform(-120, 120, 4) for a in axes}}]


def _hand_errors(machine: str, desc, rng) -> tuple[HandMachine, HandMachine, dict]:
    """The nominal hand-written machine, one with every location error (and the linear axes' squareness where its
    form is ISO 230-1's) at random, and those values by deviation name (rad, mm)."""
    nominal, hand = HandMachine(machine), HandMachine(machine)
    values = {}
    for d in generated(desc):
        if d.role == "squareness":
            if hand.squareness != "motion":  # the thesis machine's rigid form: tests/test_chain.py
                continue
            letter, about = SQUARENESS[d.symbol]
            values[d.name] = rng.choice([-1.0, 1.0]) * ORIENTATION_RAD
            hand.tilts.setdefault(letter, np.zeros(3))[about] += values[d.name]
            continue
        body, role, comp = body_of(d.symbol, hand)
        v = rng.choice([-1.0, 1.0]) * (POSITION_MM if role == "position" else ORIENTATION_RAD) * rng.uniform(0.5, 1)
        values[d.name] = v
        eps, delta = hand.errors.setdefault(body, (np.zeros(3), np.zeros(3)))
        target = delta if role == "position" else eps
        target += v * hand.error_axis(d.symbol)
    return nominal, hand, values


def _spindle_rotation(hand: HandMachine, q: dict) -> np.ndarray:
    """The spindle body's rotation (3, 3) at commands ``q``: the spindle's orientation error, then each tool-side
    axis' rotation and its body's orientation error, from the spindle down to the bed (translations do not turn)."""
    R = rodrigues(hand.errors.get("C1", (np.zeros(3),))[0])
    for letter in reversed(hand.tool):
        if hand.rotary(letter):
            R = hand.motion(letter, q[letter], np.eye(3), work=False, turn_only=True) @ R
        if letter in hand.errors:
            R = rodrigues(hand.errors[letter][0]) @ R
    return R


def _nominal_commands(nominal: HandMachine, sphere, nest, q_rot: dict) -> dict:
    """The linear commands that put the nominal nest centre on the nominal sphere centre through the nominal
    hand-written machine: W(q) − T(q) is affine in them, solved from its value at 0 and at each unit command."""
    def gap(lin):
        q = {**q_rot, **dict(zip("XYZ", lin))}
        return nominal.work_point(sphere, q) - nominal.tool_point(nest, q)

    g0 = gap(np.zeros(3))
    A = np.stack([gap(e) - g0 for e in np.eye(3)], axis=-1)
    return dict(zip("XYZ", np.linalg.solve(A, -g0)))


def reference_readings(campaign, nominal: HandMachine, hand: HandMachine, terms: dict) -> np.ndarray:
    """Every position's reading (k, 3) mm by hand: ``terms`` {(owner, base): value mm}."""
    rt, desc = campaign.rtest, campaign.machine.description
    s, p = desc.spindle.direction, desc.spindle.point
    out = []
    for run in rt.runs:
        nest = rt.nests[run.nest]
        place = rt.placement_of(run)
        t = {b: terms.get((run.nest, b), 0.0) for b in ("xNR", "yNR", "zNR", "dLR")}
        nest_nominal = p + nest.length * s
        nest_actual = p + (nest.length + t["dLR"]) * s + np.array([t["xNR"], t["yNR"], t["zNR"]])
        sphere_actual = run.sphere + np.array([terms.get((place, b), 0.0) for b in ("xPR", "yPR", "zPR")])
        z = np.array([terms.get((run.id, b), 0.0) for b in ("xZR", "yZR", "zZR")])
        for j in range(run.positions):
            q_rot = {a: np.deg2rad(run.angles_deg.get(a, np.zeros(run.positions))[j]) for a in _rotary_of(desc)}
            q = {**q_rot, **_nominal_commands(nominal, run.sphere, nest_nominal, q_rot)}
            S, N = hand.work_point(sphere_actual, q), hand.tool_point(nest_actual, q)
            G = _spindle_rotation(hand, q)
            d = G.T @ (S - N)
            if run.frame == "machine":
                d = _spindle_rotation(nominal, q) @ d
            out.append(d - z)
    return np.array(out)


def _rotary_of(desc) -> list[str]:
    return [a.letter for a in desc.rotary_axes]


def _model_and_theta(campaign, values: dict, rng):
    """The chain's R-test model over every deviation of ``values`` and every R-test term, and the parameter vector
    of those values with random nuisance terms; the terms by (owner, base)."""
    space = described_space(campaign, deviations=list(values), data="rtest")
    model = RTestModel(campaign, space)
    terms = {(p.owner, p.base): rng.uniform(-1, 1) * TERM_MM[p.base] for p in space.parameters if p.group == "rtest"}
    theta = space.vector({**values, **{f"{b}[{o}]": v for (o, b), v in terms.items()}})
    return model, theta, terms


@pytest.mark.parametrize("machine", list(BUILTIN_TYPES))
@pytest.mark.parametrize("frame", ["tool", "machine"])
@pytest.mark.parametrize("zero", ["first", "absolute"])
def test_model_is_the_hand_written_rtest(machine, frame, zero):
    """Every reading of two runs (the frame and zero under test, and the other two on another sphere and nest) with
    every location error of the machine and every nuisance term at random equals the hand-written one to 1e-9 mm,
    in one batch with the nominal parameters; the errors move the readings by microns (the check can fail)."""
    rng = np.random.default_rng(sum(map(ord, machine + frame + zero)))
    campaign = parse_campaign(campaign_text(machine, _reference_runs(machine, frame, zero, rng),
                                            nests={"N1": (130.0, False), "N2": (210.0, False)}))
    desc = campaign.machine.description
    nominal, hand, values = _hand_errors(machine, desc, rng)
    model, theta, terms = _model_and_theta(campaign, values, rng)
    assert {b for _, b in terms} >= {"xPR", "dLR"} and ("r1", "xZR") in terms or zero == "absolute"
    got = model.predict(np.stack([np.zeros_like(theta), theta]))
    want = reference_readings(campaign, nominal, hand, terms).reshape(-1)
    assert np.max(np.abs(got[1] - want)) < 1e-9, np.max(np.abs(got[1] - want))
    assert np.max(np.abs(got[0])) < 1e-9  # the nominal machine puts the nest on the sphere
    assert np.max(np.abs(want)) > 1e-3


@pytest.mark.parametrize("machine", list(BUILTIN_TYPES))
def test_rtest_is_the_probe_turned(machine):
    """SPEC §22's relation: with the probe's stylus where the nest is (its length and centring the nest's, its
    sphere's placement the R-test's), S − N = A (q_probe − q_nominal), A the actual directions of the linear axes;
    the tool-frame reading with an absolute zero is that vector in the sensors' axes, G (d) = A (q_probe − q_nominal),
    to 1e-9 mm."""
    rng = np.random.default_rng(sum(map(ord, machine)) + 7)
    axes = _rotary(machine)
    angles = {a: rng.uniform(-100, 100, 6) for a in axes}
    run = {"id": "r1", "nest": "N1", "sphere": [90.0, 40.0, 70.0], "frame": "tool", "zero": "absolute",
           "angles": angles}
    angle_text = ", ".join(f"{a} = {_toml_list(v)}" for a, v in angles.items())
    probe = ("\n[probe]\nrepeatability_um = 0.5\n[probe.styli.N1]\nlength_mm = 160.0\n[[probe.runs]]\nid = \"p1\"\n"
             f"stylus = \"N1\"\nsphere_mm = [90.0, 40.0, 70.0]\nangles_deg = {{{angle_text}}}\n"
             f"centres_mm = [[{', '.join(['[0.0, 0.0, 0.0]'] * 6)}]]\n")
    campaign = parse_campaign(campaign_text(machine, [run], nests={"N1": (160.0, False)}, extra=probe))
    desc = campaign.machine.description
    nominal, hand, values = _hand_errors(machine, desc, rng)
    model, theta, terms = _model_and_theta(campaign, values, rng)
    d = model.predict(theta).reshape(-1, 3)
    probe_space = described_space(campaign, deviations=list(values), data="probe")
    same = {"xS": "xNR", "yS": "yNR", "zS": "zNR", "dRS": "dLR", "xP": "xPR", "yP": "yPR", "zP": "zPR"}
    owner = {"xNR": "N1", "yNR": "N1", "zNR": "N1", "dLR": "N1", "xPR": "r1", "yPR": "r1", "zPR": "r1"}
    probe_theta = probe_space.vector({**values, **{p.name: terms[(owner[same[p.base]], same[p.base])]
                                                   for p in probe_space.parameters if p.group == "probe"}})
    q_probe = ProbeModel(campaign, probe_space).readings(probe_theta)[0]  # (k, 3) the commanded X, Y, Z
    q_nominal = np.stack([model.layout.linear[a] for a in "XYZ"], axis=-1)
    A = np.stack([rodrigues(hand.tilts.get(a, np.zeros(3))) @ np.eye(3)[i] for i, a in enumerate("XYZ")], axis=-1)
    for j in range(len(d)):
        q = {a: np.deg2rad(angles[a][j]) for a in axes} | {a: q_nominal[j, i] for i, a in enumerate("XYZ")}
        G = _spindle_rotation(hand, q)
        np.testing.assert_allclose(G @ d[j], A @ (q_probe[j] - q_nominal[j]), rtol=0, atol=1e-9)
    assert np.max(np.abs(q_probe - q_nominal)) > 1e-3


# --------------------------------------------------------------------------- the format
GOOD_RUN = {"id": "r1", "nest": "N1", "sphere": [100.0, 0.0, 50.0], "frame": "tool", "zero": "first",
            "angles": {"A": [0.0, 0.0, 0.0], "C": [0.0, 90.0, 180.0]}, "repeats": 2}


def _good_text() -> str:
    return campaign_text("trunnion", [GOOD_RUN], nests={"N1": (120.0, False)})


@pytest.mark.parametrize("change, key, fragment", [
    (("angles_deg = {A = [0, 0, 0], C = [0, 90, 180]}", "angles_deg = {A = [0, 0], C = [0, 90, 180]}"),
     "rtest.runs[0].angles_deg", "differ in length"),
    (("displacement_um = [[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], ",
      "displacement_um = [[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], "), "rtest.runs[0].displacement_um", "rows of different"),
    (("displacement_um = [[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]], [[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], "
      "[0.0, 0.0, 0.0]]]", "displacement_um = [[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]]"),
     "rtest.runs[0].displacement_um", "3 positions"),
    (("displacement_um = [[[0.0, 0.0, 0.0], ", "displacement_um = [[[0.0, 0.0], "),
     "rtest.runs[0].displacement_um[0]", "rows of different"),
    (("[0.0, 0.0, 0.0]", "[0.0, 0.0]", "every"), "rtest.runs[0].displacement_um", "shape n x n x 3, got 2 x 3 x 2"),
    (('frame = "tool"', 'frame = "nest"'), "rtest.runs[0].frame", "unknown frame 'nest'"),
    (('zero = "first"', 'zero = "master"'), "rtest.runs[0].zero", "unknown zero 'master'"),
    (('nest = "N1"', 'nest = "N9"'), "rtest.runs[0].nest", "no nest 'N9'"),
    (("angles_deg = {A = ", "angles_deg = {B = "), "rtest.runs[0].angles_deg.B", "not a rotary axis"),
    (("sphere_mm = [100, 0, 50]", "sphere_mm = [100, nan, 50]"), "rtest.runs[0].sphere_mm[1]", "NaN"),
    (("displacement_um = [[[0.0, 0.0, 0.0], ", "displacement_um = [[[nan, 0.0, 0.0], "),
     "rtest.runs[0].displacement_um[0][0][0]", "NaN"),
    (("length_mm = 120.0", "length_mm = nan"), "rtest.nests.N1.length_mm", "NaN"),
])
def test_bad_rtest_input(run_cli, tmp_path, change, key, fragment):
    """Each bad input is one line naming the file and the key, exit 2, nothing written, no traceback."""
    text = _good_text()
    assert change[0] in text, change[0]
    path = tmp_path / "bad.toml"
    path.write_text(text.replace(change[0], change[1], -1 if len(change) > 2 else 1))
    with pytest.raises(InputError, match=fragment):
        load_campaign(path)
    code, out, err = run_cli("sample", path, "--data", "rtest", "--sampler", "exact", "-o", tmp_path / "out.nc")
    assert code == 2 and out == "" and "Traceback" not in err, err
    lines = err.splitlines()
    assert len(lines) == 1 and str(path) in lines[0] and f": {key}: " in lines[0] and fragment in lines[0], err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.toml"]


def test_good_rtest_input_loads_and_round_trips(tmp_path):
    """The good campaign of the bad inputs loads (internal units: mm, rad; defaults: the frame and zero given, the
    placement the run's own), and save -> load -> save gives the same bytes, the R-test intact."""
    path = tmp_path / "c.toml"
    path.write_text(_good_text().replace('frame = "tool"', 'frame = "machine"').replace(
        "displacement_um = [[[0.0, 0.0, 0.0], ", "displacement_um = [[[3.1, -4.0, 0.2], "))
    c = load_campaign(path)
    run = c.rtest.runs[0]
    assert run.frame == "machine" and run.zero == "first" and c.rtest.placement_of(run) == "r1"
    assert run.displacements.shape == (2, 3, 3) and run.displacements[0, 0, 0] == pytest.approx(3.1e-3)
    assert run.angles["C"][1] == pytest.approx(np.pi / 2)
    save_campaign(c, tmp_path / "a.toml")
    save_campaign(load_campaign(tmp_path / "a.toml"), tmp_path / "b.toml")
    assert (tmp_path / "a.toml").read_bytes() == (tmp_path / "b.toml").read_bytes()
    again = load_campaign(tmp_path / "b.toml").rtest
    np.testing.assert_array_equal(again.runs[0].displacements, run.displacements)
    assert again.nests == c.rtest.nests and again.runs[0].frame == "machine"


def test_calibrated_nest_and_shared_placement_have_their_terms():
    """A calibrated nest has no terms; runs with an equal sphere share one placement, a run naming one has it; a
    run zeroed absolutely has no zero terms."""
    runs = [dict(GOOD_RUN, id="a"), dict(GOOD_RUN, id="b", zero="absolute"),
            dict(GOOD_RUN, id="c", nest="N2", placement="P")]
    c = parse_campaign(campaign_text("trunnion", runs, nests={"N1": (120.0, False), "N2": (80.0, True)}))
    owners = {}
    for o, b in c.rtest.nuisance_terms(c.machine.description):
        owners.setdefault(o, []).append(b)
    assert owners == {"a": ["xZR", "yZR", "zZR", "xPR", "yPR", "zPR"], "c": ["xZR", "yZR", "zZR"],
                      "P": ["xPR", "yPR", "zPR"], "N1": ["xNR", "yNR", "dLR"]}


# --------------------------------------------------------------------------- the data choices
def test_data_choices_keep_their_meaning():
    """``rtest`` is the R-test alone, ``all`` every instrument the campaign has, ``both`` still the ball bar and the
    probe (refused on a campaign without probe readings), and ``rtest`` refused without R-test runs."""
    from mtmcal_bayes.errors import ParameterError

    c = parse_campaign(_good_text())
    for data in ("rtest", "all"):
        m = make_model("linear", c, data=data)
        assert len(m.observations) == 9 and m.observations.instrument == "rtest"
    with pytest.raises(ParameterError, match="touch-probe readings"):
        make_model("linear", c, data="both")
    demo = load_campaign(None)
    with pytest.raises(ParameterError, match="R-test"):
        make_model("linear", demo, data="rtest")


def _with_rtest(text: str, machine: str) -> str:
    """``text`` (a campaign) with an ``[rtest]`` of one run on ``machine`` appended."""
    axes = _rotary(machine)
    run = dict(GOOD_RUN, angles={axes[0]: [0.0, 20.0, 40.0], axes[1]: [0.0, 90.0, 180.0]})
    rtest = campaign_text(machine, [run], nests={"N1": (120.0, False)})
    return text + "\n" + rtest[rtest.index("[rtest]"):]


@pytest.mark.parametrize("machine", [THESIS_TYPE, "trunnion"])
def test_combinations_stack_the_instruments_unchanged(machine):
    """On a campaign with all three instruments (the thesis campaign, the trunnion's demo, each with an R-test run
    added): ``ballbar+rtest``, ``probe+rtest`` and ``all`` stack the ball bar's, the probe's and the R-test's own
    models (their observations in that order, each part's prediction of a random batch equal to the part's own on its
    own space), ``both`` keeps the ball bar and the probe alone, and ``all`` has one discrepancy scale per
    instrument."""
    from mtmcal_bayes.datasets import builtin_campaign_text
    from mtmcal_bayes.inference.log_posterior import LogPosterior

    base = builtin_campaign_text()[0] if machine == THESIS_TYPE else \
        (Path(mtmcal_bayes.__file__).parent / "datasets" / "machines" / f"{machine}-demo.toml").read_text()
    c = parse_campaign(_with_rtest(base, machine))
    rng = np.random.default_rng(3)
    alone = {d: LogPosterior(c, "linear", data=d) for d in ("ballbar", "probe", "rtest")}
    for data, parts in (("ballbar+rtest", ("ballbar", "rtest")), ("probe+rtest", ("probe", "rtest")),
                        ("all", ("ballbar", "probe", "rtest")), ("both", ("ballbar", "probe"))):
        post = LogPosterior(c, "linear", data=data)
        assert post.scales == tuple({"ballbar": "sigma_model"}.get(i, f"sigma_model_{i}") for i in parts)
        theta = rng.normal(0.0, 1e-3, (3, post.p))
        got = post.forward.predict(theta)
        start = 0
        for instrument in parts:
            own = alone[instrument]
            cols = [post.space.index(n) for n in own.space.names]
            want = own.forward.predict(theta[:, cols])
            np.testing.assert_allclose(got[:, start:start + want.shape[1]], want, rtol=1e-12, atol=1e-15)
            start += want.shape[1]
        assert start == got.shape[1]


# --------------------------------------------------------------------------- the posterior against a truth
def _recovery_runs(machine: str) -> list[dict]:
    """Each rotary axis swept alone and with the other held, on two spheres with two nests, both frames and
    zeros."""
    a1, a2 = _rotary(machine)
    sweep = [-90.0, -45.0, 0.0, 45.0, 90.0]
    hold = [0.0] * 5

    def angles(first, second):
        return {a1: first, a2: second}

    return [
        {"id": "r1", "nest": "N1", "sphere": [120.0, 40.0, 80.0], "frame": "tool", "zero": "first",
         "angles": angles(sweep, hold), "repeats": 2},
        {"id": "r2", "nest": "N1", "sphere": [120.0, 40.0, 80.0], "frame": "machine", "zero": "absolute",
         "angles": angles(hold, [x * 2 / 3 for x in sweep]), "repeats": 2},
        {"id": "r3", "nest": "N2", "sphere": [-80.0, 90.0, 150.0], "frame": "tool", "zero": "absolute",
         "angles": angles(sweep, [30.0] * 5), "repeats": 2},
        {"id": "r4", "nest": "N2", "sphere": [-80.0, 90.0, 150.0], "frame": "machine", "zero": "first",
         "angles": angles([45.0] * 5, [x * 2 / 3 for x in sweep]), "repeats": 2},
    ]


@pytest.mark.parametrize("machine", list(BUILTIN_TYPES))
def test_sample_rtest_recovers_the_stated_truth(machine):
    """A campaign of R-test runs simulated (chain, with noise) from a stated truth (every sampled deviation 5–15 ″
    or µm, a placement and the nest's terms off zero): ``sample --data rtest`` (exact sampler) puts every deviation
    the R-test determines within 4 posterior sd of its truth, and it determines several."""
    rng = np.random.default_rng(sum(map(ord, machine)) + 11)
    desc = builtin_description(machine)
    bare = parse_campaign(campaign_text(machine, _recovery_runs(machine),
                                        nests={"N1": (150.0, False), "N2": (250.0, True)}))
    names = [p.name for p in parameter_space(bare, False, "rtest").parameters if p.group == "deviation"]
    table = quantities(desc)
    truth_lines = ["[truth.deviations]"] + [
        f'"{n}_{table[n].unit}" = {rng.choice([-1, 1]) * rng.uniform(5, 15):.3f}' for n in names]
    truth_lines += ["[truth.rtest.r1]", "xPR_um = 40.0", "yPR_um = -25.0", "zPR_um = 15.0",
                    "[truth.rtest.N1]", "dLR_um = 8.0"]
    text = campaign_text(machine, _recovery_runs(machine), nests={"N1": (150.0, False), "N2": (250.0, True)},
                         extra="\n" + "\n".join(truth_lines) + "\n")
    c = parse_campaign(text)
    sim = synthetic_campaign(c, c.truth, "chain", noise=True, seed=5)
    result = api.sample(sim, sampler="exact", seed=1, data="rtest")
    s = result.summary
    determined = [n for n in names if s.loc[n, "identification"] == DETERMINED]
    assert len(determined) >= 3, s["identification"]
    for n in determined:
        truth = c.truth.deviations[n]
        display = truth * (1e3 if table[n].unit == "um" else 180 / np.pi * 3600)
        z = (s.loc[n, "mean"] - display) / s.loc[n, "sd"]
        assert abs(z) <= 4.0, (n, s.loc[n, "mean"], display, s.loc[n, "sd"])


def test_thesis_type_rtest_keeps_the_thesis_names():
    """On the thesis machine's description the R-test model's parameters are its thirteen names (and its terms)."""
    c = parse_campaign(campaign_text(THESIS_TYPE, [dict(GOOD_RUN, angles={"B": [0.0, 30.0, 60.0],
                                                                           "C": [0.0, 90.0, 180.0]})],
                                     nests={"N1": (120.0, False)}))
    m = make_model("linear", c, data="rtest")
    assert "dx_BT" in m.space.names and "xPR[r1]" in m.space.names


def test_identify_and_report_of_an_rtest_campaign(run_cli, tmp_path):
    """``identify`` of a campaign of R-test runs alone is the least squares of its R-test readings; ``report`` writes
    its R-test sections (tests/test_report_rtest.py checks them)."""
    path = tmp_path / "c.toml"
    last = "[[0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]]]"  # the second repeat: some scatter
    path.write_text(_good_text().replace(last, "[[0.4, -0.3, 0.2], [0.1, 0.0, 0.3], [0.0, 0.2, -0.1]]]"))
    code, out, err = run_cli("identify", path)
    assert code == 0 and "all data" in out, err
    code, out, err = run_cli("report", path, "-o", tmp_path / "report")
    assert code == 0 and "rtest.png" in out and "rtest_terms.csv" in out, err
