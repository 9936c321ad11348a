"""Deterministic identification: the thesis tables, and exact inversion of the linear model."""

import numpy as np
import pytest

from mtmcal_bayes import IDENTIFIABLE, LinearModel, identify, identify_ballbar, units
from mtmcal_bayes.plugins.thesis.identification import in_machine_frame
from mtmcal_bayes.io import parse_campaign
from mtmcal_bayes.observations import with_observations

from .conftest import DATA

ARCSEC = units.ARCSEC


def test_table_4_5_reproduced(thesis):
    """All eight quantities of thesis Table 4.5 within 0.01″ / 0.01 µm (from the repeats)."""
    result = identify(thesis)
    for name in IDENTIFIABLE:
        ident = result.ballbar[name]
        assert ident.reported is not None
        assert abs(ident.difference) < 0.01, (name, ident.display, ident.reported_display)
        assert ident.reproduced


def _random_truth(space, rng, dx_BT=0.0):
    theta = np.zeros(len(space))
    for p in space.parameters:
        if p.group == "deviation":
            theta[space.index(p.name)] = rng.normal(0, 60 * ARCSEC) if p.kind == "angle" else rng.normal(0, 0.1)
    theta[space.index("dx_BT")] = dx_BT
    return theta


@pytest.mark.parametrize("seed", range(5))
def test_identification_inverts_linear_model(thesis, seed):
    """Nuisance zero and dx_BT = 0 (the thesis assumption): Eqs 4.10–4.18 on the offsets in the machine frame (each
    run read in its convention: the built-in campaign reads its B runs otherwise than the thesis) return the truth
    exactly."""
    model = LinearModel(thesis)
    theta = _random_truth(model.space, np.random.default_rng(seed))
    simulated = with_observations(thesis, model.predict(theta))
    ident = identify_ballbar(in_machine_frame(simulated) or simulated)
    expected = {n: theta[model.space.index(n)] for n in IDENTIFIABLE if n != "dx_CZ_minus_dx_BT"}
    expected["dx_CZ_minus_dx_BT"] = theta[model.space.index("dx_CZ")] - theta[model.space.index("dx_BT")]
    for name, value in expected.items():
        scale = ARCSEC if name[0] in "abg" else 1e-3
        assert ident[name].value == pytest.approx(value, abs=1e-9 * scale), name


def test_dx_BT_biases_beta_XB_as_stated(thesis):
    """SPEC §9.1: Eq 4.13 biases beta_XB by dx_BT/R_B (5.8″ per 10 µm)."""
    model = LinearModel(thesis)
    theta = _random_truth(model.space, np.random.default_rng(11), dx_BT=0.010)
    simulated = with_observations(thesis, model.predict(theta))
    ident = identify_ballbar(in_machine_frame(simulated) or simulated)
    R_B = thesis.ballbar.setups["RB1"].R_B
    bias = ident["beta_XB"].value - theta[model.space.index("beta_XB")]
    assert bias == pytest.approx(0.010 / R_B, rel=1e-9)
    assert bias / ARCSEC == pytest.approx(5.79, abs=0.01)


def test_without_second_tool_length(run_cli):
    text = (DATA / "minimal_one_repeat.toml").read_text()
    text = text[: text.rindex("[[ballbar.runs]]")]  # drop CR at RB2
    ident = identify_ballbar(parse_campaign(text, "no_cr2.toml"))
    for name in ("alpha_BT", "dy_CZ"):
        assert ident[name].value is None
        assert "second tool length" in ident[name].missing
    assert ident["beta_XB"].value is not None


def test_thesis_checks_report_cr_tension(thesis):
    checks = identify(thesis).checks
    assert any("-9.73 µm" in c and "-40.1″" in c for c in checks), checks
