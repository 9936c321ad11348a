"""The built-in type ``nutating-head`` (issue 43: a 45° B head on the tool side, a C table) and its demo campaign:
the chain against the kinematics written without the package's model code (tests/test_inclined_axes.py's
``HandNutating``: each rotary axis a Rodrigues rotation about its actual line) for every ball-bar point and probe
position of the demo; what the demo determines, as docs/machines.md states it; the posterior against the stated
truth, in posterior sd; simulation-based calibration with every instrument."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.inference import LogPosterior
from mtmcal_bayes.inference.identifiability import campaign_identifiability
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.machines.deviations import generated
from mtmcal_bayes.models.ballbar import BallbarModel, ChainKernel
from mtmcal_bayes.models.probe import ChainProbeKernel, ProbeLayout

from .test_inclined_axes import NUTATING_ERRORS, HandNutating

DOC = Path(__file__).resolve().parents[1] / "docs" / "machines.md"
#: the type's B point and spindle point, mm (datasets/machines/nutating-head.toml)
B_POINT, SPINDLE_POINT = (0.0, 0.0, 440.0), (0.0, 0.0, 300.0)


@pytest.fixture(scope="module")
def demo():
    return mb.load_campaign(demo_campaign("nutating-head"))


@pytest.fixture(scope="module")
def exact(demo):
    """``sample --machine nutating-head --sampler exact`` (every instrument, seed 1: what ``axes`` samples)."""
    return mb.sample(demo, sampler="exact", seed=1)


def _errors(seed: int) -> dict[str, float]:
    """Every location error of the type at random, 30–100 % of ±50 µm / ±100″ (mm, rad)."""
    rng = np.random.default_rng(seed)
    return {n: float(rng.choice([-1.0, 1.0]) * size * rng.uniform(0.3, 1.0)) for n, size in NUTATING_ERRORS.items()}


def test_the_type_is_the_hand_written_nutating_head(demo):
    """The reference's geometry is the type's: its location errors are the reference's, B's line [0, S, S] through
    (0, 0, 440), the spindle −Z from (0, 0, 300)."""
    desc = demo.machine.description
    assert {d.symbol for d in generated(desc) if d.role != "squareness"} == set(NUTATING_ERRORS)
    b = desc.axes["B"]
    np.testing.assert_allclose(b.direction, [0.0, np.sqrt(0.5), np.sqrt(0.5)], atol=1e-15)
    np.testing.assert_array_equal(b.point, B_POINT)
    np.testing.assert_array_equal(desc.spindle.point, SPINDLE_POINT)
    np.testing.assert_array_equal(desc.spindle.direction, [0.0, 0.0, -1.0])


@pytest.mark.parametrize("seed", [1, 2])
def test_every_ball_bar_point_and_probe_position_of_the_demo_is_the_hand_written_kinematics(demo, seed):
    """Every location error at random (two seeds): (a) the bar's length at every point of every ball-bar run of the
    demo (and at its W ball's placement), the W ball placed where the actual tool ball is at the placement's
    commands; (b) every probe position's reading, the commanded X, Y, Z at which the actual stylus centre reaches
    the actual sphere centre: the package's chain kernels equal the reference to 1e-9 mm, and the errors move both
    by microns."""
    desc = demo.machine.description
    e = _errors(seed)
    hand = HandNutating(e, b_point=B_POINT, spindle_point=SPINDLE_POINT)
    dev = {n: np.array([v]) for n, v in e.items()}

    pts = BallbarModel(demo).points()
    k = len(pts.length)
    zeros = {b: np.zeros((1, k)) for b in ("xT", "yT", "zT", "dRB")}
    kernel = ChainKernel(desc)
    got = kernel.lengths(pts, dev, zeros, np.zeros((1, k, 3)))[0]
    nominal = kernel.lengths(pts, {}, zeros, np.zeros((1, k, 3)))[0]

    def q_at(j: int) -> dict:
        return {a: float(v[j]) for a, v in pts.q.items()}

    def tool(j: int) -> np.ndarray:
        return np.asarray(SPINDLE_POINT) + pts.length[j] * np.array([0.0, 0.0, -1.0])

    want = []
    for j in range(k):
        p = int(pts.placement[j])
        w_home = hand.work_inverse(hand.tool(tool(p), q_at(p)), q_at(p))
        want.append(np.linalg.norm(hand.tool(tool(j), q_at(j)) - hand.work(w_home, q_at(j))))
    want = np.array(want)
    runs = np.concatenate([np.arange(k)[s] for s in pts.runs])
    assert len(runs) > 300  # every point of the 11 runs
    assert np.max(np.abs(got - want)) < 1e-9, np.max(np.abs(got - want))
    assert np.max(np.abs(got[runs] - nominal[runs])) > 1e-3

    pk = ChainProbeKernel(desc)
    layout = ProbeLayout(demo, kernel=pk)
    n = len(layout.length)
    terms = {t: np.zeros((1, n)) for t in (*pk.terms, "xP", "yP", "zP")}
    read = pk.readings(layout, dev, terms, 1)[0]
    base = pk.readings(layout, {}, terms, 1)[0]
    want = []
    for j in range(n):
        q = {a: float(v[j]) for a, v in layout.angles.items()} | {"X": 0.0, "Y": 0.0, "Z": 0.0}
        stylus = np.asarray(SPINDLE_POINT) + (layout.length[j] - layout.ball_radius[j]) * np.array([0.0, 0.0, -1.0])
        # the linear axes carry the head alone and translate it: the commands close the gap at once
        want.append(hand.work(layout.sphere[j], q) - hand.tool(stylus, q))
    assert n == 12
    assert np.max(np.abs(read - np.array(want))) < 1e-9, np.max(np.abs(read - np.array(want)))
    assert np.max(np.abs(read - base)) > 1e-3


def _doc_table() -> dict[str, tuple[set, set, set]]:
    """docs/machines.md's table of the type in "Identifiability under each demo campaign": data -> (one by one,
    combinations, not at all)."""
    text = DOC.read_text(encoding="utf-8")
    part = text[text.index("## Identifiability under each demo campaign"):]
    part = part[part.index("### `nutating-head`"):]
    part = part[:part.index("\n## ")]
    rows = {}
    for line in part.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0] in ("ballbar", "probe", "both", "rtest", "all"):
            one, comb, none = (set() if c == "—" else set(x.strip() for x in c.split(";" if i == 1 else ","))
                               for i, c in enumerate(cells[1:]))
            rows[cells[0]] = (one, comb, none)
    return rows


def test_the_documented_identifiability_is_the_computed_one(demo):
    """The docs' table for each data choice is what the demo's Jacobian gives (the rule every output uses), and the
    demo with every instrument determines all nine deviations of the default selection one by one."""
    rows = _doc_table()
    assert set(rows) == {"ballbar", "probe", "both", "rtest", "all"}
    for data, (one, comb, none) in rows.items():
        ident = campaign_identifiability(LogPosterior(demo, "linear", data=data))
        assert one == set(ident.determined), data
        assert comb == {c.name for c in ident.combinations}, data
        assert none == set(ident.undetermined), data
    assert len(rows["all"][0]) == 9 and not rows["all"][1] and not rows["all"][2]


def _truth(campaign, names) -> dict[str, float]:
    """The stated truth of ``names`` in display units (µm, ″)."""
    unit = {p.name: p.unit for p in LogPosterior(campaign, "linear").space.parameters}
    return {n: units.from_internal(campaign.truth.deviations.get(n, 0.0), unit[n]) for n in names}


def _within(result, truth: dict, names, combinations) -> list[str]:
    """The quantities whose posterior mean lies more than 3 posterior sd from the truth (a deviation or a
    combination Σ w·truth)."""
    far = []
    s = result.summary
    for n in names:
        if abs(s.loc[n, "mean"] - truth[n]) > 3.0 * s.loc[n, "sd"]:
            far.append(f"{n}: {s.loc[n, 'mean']:.3f} ± {s.loc[n, 'sd']:.3f} against {truth[n]:.3f}")
    for c in combinations:
        want = sum(w * truth[k] for k, w in c["weights"].items())
        if abs(c["mean"] - want) > 3.0 * c["sd"]:
            far.append(f"{c['name']}: {c['mean']:.3f} ± {c['sd']:.3f} against {want:.3f}")
    return far


def test_the_posterior_with_every_instrument_finds_the_stated_truth(demo, exact):
    """``sample --machine nutating-head --sampler exact`` (every instrument, seed 1): each of the nine deviations'
    posterior mean lies within 3 posterior sd of the truth the readings were simulated from (the chain, with noise),
    and the posterior is narrower than 2 µm / 2″ on each: the truth is found, not merely not excluded."""
    r = exact
    names = [p.name for p in r.log_posterior.space.parameters if p.group == "deviation"]
    assert len(names) == 9 and set(names) == set(demo.truth.deviations)
    assert not _within(r, _truth(demo, names), names, [])
    assert (r.summary.loc[names, "sd"] < 2.0).all()


def test_the_chain_model_on_ball_bar_and_probe_finds_the_stated_truth(demo):
    """The chain model sampled (emcee, seed 1) on the ball bar's and the probe's data: what they determine — five
    deviations one by one and three combinations — lies within 3 posterior sd of the truth."""
    r = mb.sample(demo, model="chain", data="both", seed=1)
    ident = r.identifiability
    assert len(ident.determined) == 5 and len(r.combinations) == 3
    names = [p.name for p in r.log_posterior.space.parameters if p.group == "deviation"]
    far = _within(r, _truth(demo, names), ident.determined, r.combinations)
    assert not far, far


# ------------------------------------------------------------------------------- controllers: axes and the ISG CSV

def _rotate(v: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``v`` (3,) turned by each rotation vector of ``w`` (n, 3) rad (Rodrigues' formula): (n, 3)."""
    angle = np.linalg.norm(w, axis=1, keepdims=True)
    k = w / np.where(angle > 0, angle, 1.0)
    return (v * np.cos(angle) + np.cross(k, v) * np.sin(angle) + k * (k @ v)[:, None] * (1.0 - np.cos(angle)))


def test_the_isg_csv_gives_the_inclined_line_from_the_posterior(exact):
    """The ISG CSV of the exact posterior (what ``axes --machine nutating-head --format isg-csv`` writes:
    ``api.isg_csv`` is this text of that posterior): B's identified line as
    ``PXB PYB PZB`` (mm) and ``VXB VYB VZB``: the direction is the posterior mean of B's direction turned by each
    draw's rotation of its body (its tilts about u and v and its zero about k, by Rodrigues' formula, computed here),
    to 1e-9; the point is B's point (0, 0, 440), its position errors not estimated (a comment says so); B's errors in
    its basis are named in comments, not written under frame names; the record's other names are position errors
    of the format."""
    from mtmcal_bayes.io.isg_csv import ISG_NAMES, isg_csv
    from mtmcal_bayes.posterior.axis_lines import isg_position_errors

    lines = isg_csv(*isg_position_errors(exact)).splitlines()
    header, record = [ln for ln in lines if not ln.startswith("//")]
    values = dict(zip(header.split(), map(float, record.split())))
    line = ["PXB", "PYB", "PZB", "VXB", "VYB", "VZB"]
    assert header.split()[-6:] == line and set(values) - set(line) <= set(ISG_NAMES)

    post = exact.idata.posterior
    ru, rv, zero = (units.to_internal(np.ravel(post[n].values), "arcsec") for n in ("E_RU0B", "E_RV0B", "E_B0B"))
    k = np.array([0.0, 1.0, 1.0]) / np.sqrt(2.0)
    u, v = np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, -1.0]) / np.sqrt(2.0)
    d = _rotate(k, ru[:, None] * u + rv[:, None] * v + zero[:, None] * k).mean(axis=0)
    got = np.array([values[n] for n in line[3:]])
    assert np.max(np.abs(got - d)) < 1e-9, got - d  # the record's 9 significant digits: 5e-10 on 0.7
    assert np.linalg.norm(got - k) > 3e-5  # the tilts (about 10″) moved it
    np.testing.assert_array_equal([values[n] for n in line[:3]], B_POINT)
    comments = "\n".join(ln for ln in lines if ln.startswith("//"))
    assert "PXB PYB PZB: the description's point" in comments
    for name in ("E_RU0B", "E_RV0B"):
        assert f"{name}: an error of the inclined B axis in its own basis" in comments
    for name in ("E_U0B", "E_V0B"):
        assert f"{name}: not estimated by the machine's model (acts only through" in comments
    assert "B0B: the zero of the inclined B axis" in comments


def test_axes_writes_the_isg_csv_of_the_type(tmp_path, run_cli):
    """The command writes the same record: ``axes --machine nutating-head --format isg-csv -o FILE`` ends its
    header with B's line."""
    out = tmp_path / "b.csv"
    code, _, err = run_cli("axes", "--machine", "nutating-head", "--format", "isg-csv", "-o", str(out))
    assert code == 0, err
    header = [ln for ln in out.read_text(encoding="utf-8").splitlines() if not ln.startswith("//")][0]
    assert header.split()[-6:] == ["PXB", "PYB", "PZB", "VXB", "VYB", "VZB"]


@pytest.mark.parametrize("machine", ["trunnion", "head-head"])
def test_a_frame_aligned_type_s_isg_csv_has_no_line(machine, run_cli):
    """On a type whose axes lie along frame axes the CSV is position errors only, as before: no axis line, no
    inclined-axis comment."""
    from mtmcal_bayes.io.isg_csv import ISG_NAMES

    code, text, err = run_cli("axes", "--machine", machine, "--format", "isg-csv")
    assert code == 0, err
    header = [ln for ln in text.splitlines() if not ln.startswith("//")][0].split()
    assert header and set(header) <= set(ISG_NAMES)
    assert "inclined" not in text and "identified line" not in text


def test_the_head_angle_and_the_gauge_line_are_what_the_controller_table_says(demo, exact):
    """docs/machines.md's controller table of the type, per draw of the exact posterior: the angle between B's
    identified line and the tool (ISG KIN_TYP_33's head angle HD3) is 45° + E_A(0C1)B to first order (to 0.01″: the
    second order of angles of ~10″; B's own tilts do not enter it); the gauge line's absolute point is
    E_X(0C1)B − 0.4799 µm/″·(E_RV0B + E_B0B) along X and 140 mm × E_RU0B along Y."""
    from mtmcal_bayes.machines.chain import Chain
    from mtmcal_bayes.posterior import axis_lines as al

    r = exact
    desc = demo.machine.description
    draws = {p.name: units.to_internal(np.ravel(r.idata.posterior[p.name].values)[:500], p.unit)
             for p in r.log_posterior.space.parameters if p.group == "deviation"}
    lines = al._lines(Chain(desc, generated(desc)), desc, draws, 500)
    angle = np.arccos(np.einsum("ni,ni->n", lines["B"][1], -lines["C1"][1]))
    want = np.deg2rad(45.0) + draws["E_A(0C1)B"]
    assert np.max(np.abs(units.from_internal(angle - want, "arcsec"))) < 0.01
    assert np.ptp(units.from_internal(draws["E_A(0C1)B"], "arcsec")) > 0.1  # the draws spread: the check can fail
    # the docs' table: the gauge line's absolute X and Y (140 mm below B's pivot), to first order (1e-6 mm)
    point = lines["C1"][0]
    want_x = draws["E_X(0C1)B"] - 140.0 * np.sqrt(0.5) * (draws["E_RV0B"] + draws["E_B0B"])
    want_y = 140.0 * draws["E_RU0B"]
    assert np.max(np.abs(point[:, 0] - want_x)) < 1e-6 and np.max(np.abs(point[:, 1] - want_y)) < 1e-6
    assert np.ptp(point[:, 0]) > 1e-4


def test_the_report_s_numbers_are_the_stated_truth(tmp_path, run_cli):
    """``report --machine nutating-head -o DIR`` (every instrument: ball bar, probe, R-test): its truth table has a
    row for each of the nine deviations, all determined with every instrument, each within 3 posterior sd of the
    stated truth; the instruments are compared each alone and fused (the fused rows are the report's own posterior);
    the R-test's readings and the machine figures are drawn."""
    import csv

    code, _, err = run_cli("report", "--machine", "nutating-head", "-o", str(tmp_path))
    assert code == 0, err
    rows = list(csv.DictReader((tmp_path / "truth.csv").open(encoding="utf-8")))
    assert len(rows) == 9
    far = [r["quantity"] for r in rows if abs(float(r["z"])) > 3.0]
    assert not far, far
    compared = list(csv.DictReader((tmp_path / "instruments.csv").open(encoding="utf-8")))
    assert list(dict.fromkeys(r["data"] for r in compared)) == ["ball bar only", "probe only", "R-test only", "fused"]
    summary = {r["quantity"]: r for r in csv.DictReader((tmp_path / "summary.csv").open(encoding="utf-8"))}
    fused = [r for r in compared if r["data"] == "fused"]
    assert fused and all(float(r["mean"]) == float(summary[r["quantity"]]["mean"]) for r in fused)
    for name in ("machine.png", "deviations.png", "rtest.png", "instruments_forest.png"):
        assert (tmp_path / name).stat().st_size > 0
