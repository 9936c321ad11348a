"""The default selection of location errors, computed on every machine (SPEC §21): which errors each built-in type
leaves out, and the combination each one acts through, checked numerically on poses the rule did not use; an
explicit selection of a left-out error accepted; a nutating head; the head-head case of the SPEC."""

from __future__ import annotations

import numpy as np
import pytest

from mtmcal_bayes import units
from mtmcal_bayes.errors import InputError
from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, builtin_description, parse_description
from mtmcal_bayes.machines import selection as rule
from mtmcal_bayes.machines.deviations import generated
from mtmcal_bayes.machines.selection import SPAN, TOLERANCE, default_selection, redundant, selected, spectrum

S = float(np.sqrt(0.5))
SQUARENESS = {"E_C0X", "E_B0X", "E_A0Y"}

#: µm of shift per ″ of turn at a lever arm of ``mm``
def lever(mm: float) -> float:
    return units.from_internal(mm * units.to_internal(1.0, "arcsec"), "um")


PLACEMENT, LENGTH = "workpiece-side point's placement", "tool length"
#: per built-in type, each error the rule leaves out (squareness aside): {kept error: coefficient} and the nuisance
#: terms it also needs, derived by hand from the chain's geometry (docs/machines.md, "The default selection")
EXPECTED = {
    "integrex-i200": {
        "E_C0C": ({}, {PLACEMENT}),                                 # the outermost table's zero
        "E_X0B": ({"dx_CZ": -1.0}, set()),                          # the B line along X against the C line along X
        "E_Z0B": ({}, {PLACEMENT}),                                 # a Z shift against a table turning about Z
        "E_Y(0C1)B": ({"dy_CZ": -1.0}, set()),                      # along Y, which B turns about: a Y shift
        "E_B(0C1)B": ({"beta_XB": 1.0}, set()),                     # about Y through the B centre: B's zero
        "dz_BT": ({}, {LENGTH}),                                    # the spindle along itself: the tool's length
    },
    "vertical-turn-mill": {
        "E_C0C": ({}, {PLACEMENT}),
        "E_X0B": ({"E_X0C": -1.0}, set()),
        "E_Z0B": ({}, {PLACEMENT}),
        "E_Y(0C1)B": ({"E_Y0C": -1.0}, set()),
        "E_X(0C1)B": ({}, {LENGTH}),
        "E_B(0C1)B": ({"E_B0B": 1.0}, set()),
    },
    "trunnion": {
        "E_Z0A": ({}, {LENGTH}),                                    # the whole table along Z, the spindle's axis
        "E_C0C": ({}, {PLACEMENT}),
        # C's tilt about X through the table surface (z = −50) is A's zero plus a shift of C's line along Y:
        # ε·x̂ × (0, 0, 50 mm) = −50 mm·ε along Y
        "E_A0C": ({"E_A0A": 1.0, "E_Y0C": -lever(50.0)}, set()),
    },
    "head-head": {
        "E_X0C": ({}, {PLACEMENT}),                                 # the whole head shifted against a table that
        "E_Y0C": ({}, {PLACEMENT}),                                 # only translates
        "E_Z0A": ({}, {PLACEMENT}),                                 # along Z, C's own axis
        "E_C0A": ({"E_C0C": 1.0}, set()),                           # SPEC §21: about C's line, only the sum acts
        # about X through the gauge line: A's zero (about X through the pivot, 150 mm above) and a shift along Y
        "E_A(0C1)A": ({"E_A0A": 1.0, "E_Y(0C1)A": -lever(150.0)}, set()),
        "E_Z(0C1)A": ({}, {LENGTH}),
    },
    # B along k = [0, S, S] through (0, 0, 440), the gauge line at (0, 0, 300): u = +X, v = S·(ŷ − ẑ)
    "nutating-head": {
        "E_C0C": ({}, {PLACEMENT}),
        "E_U0B": ({"E_X0C": -1.0}, set()),                          # B's line along X against C's line along X
        "E_V0B": ({"E_Y0C": -S}, {PLACEMENT}),                      # its Y part against C's, its Z part a placement
        "E_Y(0C1)B": ({"E_Y0C": -1.0}, {LENGTH, PLACEMENT}),        # along Y, in B's plane: as the nutating test
        # about Y = k/S − ẑ through the gauge line: √2 × B's zero about its line 140 mm above, a turn about the tool's
        # own axis that moves no tool point, and the shift along X of that lever
        "E_B(0C1)B": ({"E_B0B": np.sqrt(2.0), "E_X(0C1)B": lever(140.0)}, set()),
        "E_Z(0C1)B": ({}, {LENGTH}),
    },
}


def nutating_head(b_point=(0.0, 0.0, 150.0)):
    """A nutating head written here: the C table (+Z through the origin), a B head whose axis is [0, S, S] through
    ``b_point``, the spindle along −Z from the origin (the DMU monoBLOCK kind)."""
    return parse_description({
        "configuration": "w-C'bZYXB(C1)-t",
        "axes": {"C": {"direction": "+Z", "point_mm": [0.0, 0.0, 0.0]},
                 "B": {"direction": [0.0, 0.70710678, 0.70710678], "point_mm": list(b_point),
                       "travel_deg": [-180.0, 180.0]}},
        "spindle": {"direction": "-Z", "point_mm": [0.0, 0.0, 0.0]}}, "<nutating head>", "")


def check_combinations(desc, seed: int) -> dict[str, float]:
    """Each left-out error's column minus its stated combination of kept columns, projected off the nuisance terms it
    names, relative to the column's norm, on random poses of another seed than the rule's: ``{name: residual}``."""
    errs = rule.rule_order(desc)
    saved = rule.SEED
    rule.SEED = seed
    try:
        J, N, kinds = rule.columns(desc, errs)
    finally:
        rule.SEED = saved
    col = {d.name: J[:, i] for i, d in enumerate(errs)}
    sel = default_selection(desc)
    out = {}
    for name, lo in sel.left_out.items():
        if name not in col:
            continue
        r = col[name] - sum(a * col[k] for k, a in lo.weights.items())
        mask = np.array([k in lo.nuisance for k in kinds])
        if mask.any():
            r = r - N[:, mask] @ np.linalg.lstsq(N[:, mask], r, rcond=None)[0]
        out[name] = float(np.linalg.norm(r) / np.linalg.norm(col[name]))
    return out


@pytest.mark.parametrize("name", list(BUILTIN_TYPES))
def test_each_builtin_leaves_out_what_its_geometry_says_with_the_combination_it_acts_through(name):
    """The errors left out (squareness aside) are those derived by hand, each with the kept errors' coefficients
    (to 1e-9 relative) and the nuisance terms it needs; and on poses of another seed each left-out column equals
    the stated combination to 1e-9 of its norm (rounding sits at 1e-15), while every kept column keeps more than 1e-3
    of its norm outside the span before it: the gap the tolerance sits in."""
    desc = builtin_description(name)
    sel = default_selection(desc)
    want = EXPECTED[name]
    assert {n for n in sel.left_out if n not in SQUARENESS and n not in
            {d.name for d in generated(desc) if d.role == "squareness"}} == set(want)
    for n, (weights, nuisance) in want.items():
        lo = sel.left_out[n]
        assert set(lo.weights) == set(weights), (n, lo.weights)
        for k, a in weights.items():
            assert lo.weights[k] == pytest.approx(a, rel=1e-9), (n, k)
        assert set(lo.nuisance) == nuisance, (n, lo.nuisance)
        assert lo.residual < 1e-12
    for n, res in check_combinations(desc, seed=7).items():
        assert res < 1e-9, (n, res)
    kept = [r for n, r in sel.residuals.items() if n not in sel.left_out]
    assert min(kept) > 1e-3 > TOLERANCE


@pytest.mark.parametrize("name", [n for n in BUILTIN_TYPES if n != "integrex-i200"])
def test_the_default_set_is_the_generated_less_the_left_out_in_generated_order(name):
    desc = builtin_description(name)
    left = redundant(desc)
    assert [d.name for d in selected(desc)] == [d.name for d in generated(desc) if d.name not in left]
    assert SQUARENESS <= set(left) and all("measured by other means" in left[s] for s in SQUARENESS)


def test_the_singular_values_show_the_gap():
    """As many singular values of the unit-norm columns (nuisance and errors) sit below 1e-12 as errors are left out
    (squareness aside), and the smallest of the others is above 1e-2: thirteen orders of magnitude apart."""
    for name in BUILTIN_TYPES:
        desc = builtin_description(name)
        sv = spectrum(desc)
        n_left = sum(1 for n in default_selection(desc).left_out if n not in
                     {d.name for d in generated(desc) if d.role == "squareness"})
        assert (sv < 1e-12).sum() == n_left, name
        assert sv[sv >= 1e-12].min() > 1e-2, name


def test_head_head_E_C0A_acts_only_through_its_sum_with_E_C0C():
    """SPEC §21's example: the A fork's pivot lies on C's line, so E_C0A and E_C0C turn about one line and only their
    sum acts; §19's list kept both."""
    desc = builtin_description("head-head")
    lo = default_selection(desc).left_out["E_C0A"]
    assert lo.weights == {"E_C0C": 1.0} and lo.nuisance == ()
    assert lo.why.startswith("acts only through E_C0C + E_C0A")
    assert "E_C0C" in [d.name for d in selected(desc)] and "E_C0A" not in [d.name for d in selected(desc)]


def test_the_pivot_off_C_s_line_moves_the_combination():
    """The same head-head with the fork's pivot 40 mm off C's line along X: E_C0A still turns about a line parallel
    to C's, so it is C's zero plus a shift of A's line, −40 mm·ε along Y (ẑ × x̂ = ŷ): the combination follows the
    geometry, not a list."""
    from dataclasses import replace

    desc = builtin_description("head-head")
    moved = tuple(replace(a, point=np.array([40.0, 0.0, 150.0])) if a.letter == "A" else a for a in desc.tool_chain)
    lo = default_selection(replace(desc, tool_chain=moved)).left_out["E_C0A"]
    assert set(lo.weights) == {"E_C0C", "E_Y0A"} and lo.nuisance == ()
    assert lo.weights["E_C0C"] == 1.0
    assert lo.weights["E_Y0A"] == pytest.approx(-lever(40.0), rel=1e-9)


def test_the_nutating_head():
    """B along [0, S, S] through (0, 0, 150), spindle −Z, C table.  Left out: C's zero (the sphere's placement); B's
    position along u = +X (−E_X0C) and along v = S·(ŷ − ẑ) (−S·E_Y0C, and a Z shift: the placement); the spindle's
    position along Y (−E_Y0C, and the tool's length along Z with the placement) and along itself (the length); its
    tilt about Y (ŷ = k/S − ẑ: √2 × B's zero about its line 150 mm above, a tilt about its own axis that does not
    move the tool point, and the shift along X of that lever, 150 mm·ε)."""
    desc = nutating_head()
    sel = default_selection(desc)
    left = {n: lo for n, lo in sel.left_out.items() if n not in SQUARENESS}
    assert set(left) == {"E_C0C", "E_U0B", "E_V0B", "E_Y(0C1)B", "E_Z(0C1)B", "E_B(0C1)B"}
    assert list(sel.kept) == ["E_X0C", "E_Y0C", "E_A0C", "E_B0C", "E_RU0B", "E_RV0B", "E_B0B", "E_X(0C1)B",
                              "E_A(0C1)B"]
    assert left["E_U0B"].weights == {"E_X0C": -1.0} and left["E_U0B"].nuisance == ()
    assert left["E_V0B"].weights["E_Y0C"] == pytest.approx(-S, rel=1e-6)  # 0.70710678 is S to 1e-8
    assert left["E_V0B"].nuisance == (PLACEMENT,)
    assert left["E_B(0C1)B"].weights["E_B0B"] == pytest.approx(np.sqrt(2.0), rel=1e-6)
    assert left["E_B(0C1)B"].weights["E_X(0C1)B"] == pytest.approx(lever(150.0), rel=1e-6)
    for n, res in check_combinations(desc, seed=11).items():
        assert res < 1e-9, (n, res)


def test_an_error_selected_explicitly_that_the_rule_leaves_out_is_accepted():
    """``deviations`` may name any generated error: the head-head's E_C0A and E_X0C are estimated when listed (their
    identifiability is then the campaign's Jacobian's to state), and the rule's reason stays for the others."""
    desc = parse_description({
        "configuration": "w-Y'X'bZCA(C1)-t",
        "axes": {"C": {"direction": "+Z", "point_mm": [0.0, 0.0, 0.0]},
                 "A": {"direction": "+X", "point_mm": [0.0, 0.0, 150.0]}},
        "spindle": {"direction": "-Z", "point_mm": [0.0, 0.0, 0.0]},
        "deviations": ["E_C0C", "E_C0A", "E_X0C"]}, "<head-head listed>", "")
    assert [d.name for d in selected(desc)] == ["E_X0C", "E_C0C", "E_C0A"]
    assert "E_C0A" in redundant(desc)  # still the rule's: the figure greys only what is not chosen
    with pytest.raises(InputError, match="is not a deviation of this machine"):
        parse_description({"configuration": "w-Y'X'bZCA(C1)-t",
                           "axes": {"C": {"direction": "+Z"}, "A": {"direction": "+X", "point_mm": [0, 0, 150]}},
                           "spindle": {"direction": "-Z"}, "deviations": ["E_W0C"]}, "<bad>", "")


def test_the_thesis_machine_keeps_its_thirteen():
    desc = builtin_description("integrex-i200")
    assert [d.name for d in selected(desc)] == [d.name for d in generated(desc) if d.name in set(desc.deviations)]
    assert len(selected(desc)) == 13


def test_the_tool_ball_s_offset_across_the_spindle_is_not_in_the_span():
    """The trunnion's A line along Y is, column for column, the tool ball's offset across the spindle (the tool side
    only translates): a free stylus cannot tell them apart, the centred T ball of the ball bar can, and the rule
    keeps it (SPAN holds the tool's length and the workpiece-side point's placement only)."""
    assert SPAN == ("tool length", PLACEMENT)
    desc = builtin_description("trunnion")
    errs = rule.rule_order(desc)
    J, N, kinds = rule.columns(desc, errs)
    across = N[:, [k == "tool offset across the spindle" for k in kinds]]
    c = J[:, [d.name for d in errs].index("E_Y0A")]
    r = c - across @ np.linalg.lstsq(across, c, rcond=None)[0]
    assert np.linalg.norm(r) < 1e-12 * np.linalg.norm(c)
    assert "E_Y0A" in default_selection(desc).kept


ROOT = __import__("pathlib").Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("name", ["trunnion", "vertical-turn-mill", "head-head"])
def test_each_demo_s_truth_re_expressed_predicts_its_readings(name):
    """The demo's [truth] (on the kept errors, with the nuisance terms the left-out ones became) and the truth its
    readings were simulated from (bench/simulate_truths) predict the same observations, ball bar and probe: to 1e-9 mm
    through the first-order model, and through the exact chain to 2e-5 mm (the second order of the truth's angles of
    ≤ 20″ on lever arms of a few hundred mm; 1/25 of the bar's 0.5 µm accuracy).  Its [truth] names no left-out
    error."""
    from mtmcal_bayes.io import load_campaign
    from mtmcal_bayes.io.campaign_reader import load_truth
    from mtmcal_bayes.io.machine_reader import demo_campaign
    from mtmcal_bayes.machines.space import described_space
    from mtmcal_bayes.models import make_model
    from mtmcal_bayes.simulation.simulate import truth_vector

    c = load_campaign(demo_campaign(name))
    old = load_truth(ROOT / "bench" / "simulate_truths" / f"{name}.toml", c)
    desc = c.machine.description
    assert not set(c.truth.deviations) & set(redundant(desc))
    names = [d.name for d in generated(desc) if d.name in old.deviations or d.name in c.truth.deviations]
    space = described_space(c, names, data="both")
    theta_old, theta_new = truth_vector(space, old), truth_vector(space, c.truth)
    for model, tol in (("linear", 1e-9), ("chain", 2e-5)):
        m = make_model(model, c, space, data="both")
        pred = m.predict(np.stack([theta_old, theta_new]))
        assert np.abs(pred[0] - pred[1]).max() < tol, (model, np.abs(pred[0] - pred[1]).max())


def test_a_target_the_default_leaves_out_is_refused_with_the_rule_s_reason(run_cli):
    """``plan --target E_C0A`` on the head-head: one line naming the flag, why it is not estimated (the combination it
    acts through) and what may be targeted; exit 2."""
    code, out, err = run_cli("plan", "--machine", "head-head", "--target", "E_C0A")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "--target: 'E_C0A' is not estimated on this machine (acts only through E_C0C + E_C0A" in err
    assert "expected one of: E_A0C, E_B0C, E_C0C" in err
