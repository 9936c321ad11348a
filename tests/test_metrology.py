"""The metrologist's language: GUM statements, tolerance decisions (ISO 14253-1), identifiability through
nuisance priors, ISO symbols on every output path (docs/metrology.md)."""

import json
import math

import numpy as np
import pandas as pd
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.arviz_import import az
from mtmcal_bayes.campaign import Tolerance
from mtmcal_bayes.inference import reading_choice
from mtmcal_bayes.inference.gum import K_GAUSSIAN, gum_statement, numerical_tolerance
from mtmcal_bayes.iso import ISO_SYMBOL
from mtmcal_bayes.posterior.conformity import conformity_table

from . import variants

EIGHT = ["alpha_CZ", "beta_CZ", "alpha_XB", "beta_XB", "gamma_XB", "alpha_BT", "dx_CZ_minus_dx_BT", "dy_CZ"]


def _idata(draws: dict) -> object:
    return az.from_dict(posterior={k: v.reshape(4, -1) for k, v in draws.items()})


def test_numerical_tolerance_is_half_the_last_digit_of_u_at_two_digits():
    assert numerical_tolerance(8.14) == pytest.approx(0.05)
    assert numerical_tolerance(0.0123) == pytest.approx(0.0005)  # 12 × 10⁻³: δ = ½ × 10⁻³
    assert numerical_tolerance(0.35) == pytest.approx(0.005)  # GUM-S1 §7.9.2 example
    assert numerical_tolerance(123.0, digits=1) == pytest.approx(50.0)


def test_gaussian_posterior_gets_U_and_k_a_heavy_tailed_one_does_not():
    """Seeded: 40 000 independent draws.  Normal: y ± 1.96u agrees with the symmetric interval to within the
    endpoints' own Monte-Carlo error, so U = 1.96 u is stated.  Student t with 3 dof (scaled to unit sd):
    y ± 1.96u lies ~0.3 sd inside the 97.5 % quantile's place, far beyond that error, so it is not."""
    rng = np.random.default_rng(5)
    idata = _idata({"alpha_XB": rng.normal(3.0, 2.0, 40_000),
                    "beta_XB": rng.standard_t(3, 40_000) / math.sqrt(3.0)})
    for name in ("alpha_XB", "beta_XB"):
        d = np.asarray(idata.posterior[name]).ravel()
        g = gum_statement(idata, name, tuple(az.hdi(d, hdi_prob=0.95)))
        assert g["u"] == pytest.approx(d.std(ddof=1))
        assert g["ci95_symmetric_low"] == pytest.approx(np.quantile(d, 0.025))
        assert g["coverage_probability"] == 0.95 and g["n_draws"] == 40_000
        if name == "alpha_XB":
            assert g["k"] == pytest.approx(K_GAUSSIAN) and g["U"] == pytest.approx(K_GAUSSIAN * g["u"])
            assert g["U_note"] == ""
        else:
            assert g["U"] is None and g["k"] is None and "not close enough to Gaussian" in g["U_note"]
        # 40 000 independent draws: endpoints known to a few hundredths of u
        assert 0 < g["endpoint_tolerance"] < 0.1 * g["u"]


def test_conformity_verdicts_and_probability():
    """Posterior N(0, 1) (seeded, 40 000 draws): the verdict follows where the 95 % interval lies."""
    rng = np.random.default_rng(1)
    idata = _idata({"alpha_XB": rng.normal(0.0, 1.0, 40_000)})
    d = np.asarray(idata.posterior["alpha_XB"]).ravel()
    lo, hi = az.hdi(d, hdi_prob=0.95)
    summary = pd.DataFrame({"mean": [d.mean()], "hdi_low": [lo], "hdi_high": [hi]}, index=["alpha_XB"])
    arcsec = mb.units.to_internal(1.0, "arcsec")

    def decide(low, high):
        tol = {"alpha_XB": Tolerance("alpha_XB", None if low is None else low * arcsec,
                                     None if high is None else high * arcsec)}
        return conformity_table(idata, summary, tol).loc["alpha_XB"]

    assert decide(-3, 3)["conformity"] == "conforms"
    assert decide(-3, 3)["p_nonconformance"] == pytest.approx(0.0027, abs=0.001)
    assert decide(-1, 1)["conformity"] == "undecided"
    assert decide(2.5, 10)["conformity"] == "does not conform"
    assert decide(None, 2.5)["conformity"] == "conforms"  # one-sided: at most 2.5
    assert decide(None, 2.5)["p_nonconformance"] == pytest.approx(np.mean(d > 2.5))
    assert math.isnan(decide(None, 2.5)["tolerance_low"])


def _tolerances(tmp_path, name: str, text: str):
    f = tmp_path / name
    f.write_text("[tolerances]\n" + text)
    return str(f)


def test_thesis_tolerance_decisions_through_the_cli(run_cli, tmp_path):
    """Acceptance: alpha_XB conforms to ±30″ and does not conform to ±10″; beta_XB is undecided against ±30″,
    with its probability of nonconformance and the planner's next measurement."""
    wide = _tolerances(tmp_path, "wide.toml", "alpha_XB_arcsec = 30\nE_B0B_arcsec = 30\n")
    code, out, err = run_cli("sample", "--json", "--seed", "1", "--quiet", "--tolerances", wide)
    assert code == 0, err
    s = json.loads(out)["summary"]
    a, b = s["alpha_XB"], s["beta_XB"]
    assert a["conformity"] == "conforms" and a["p_nonconformance"] < 0.001
    assert a["tolerance"] == {"low": -30.0, "high": 30.0}
    assert b["conformity"] == "undecided" and 0.2 < b["p_nonconformance"] < 0.95
    nxt = b["next_measurement"]
    assert nxt["name"] and nxt["sd_after"] < b["u"]
    assert nxt["sd_to_decide"] == pytest.approx(min(abs(b["mean"] + 30), abs(b["mean"] - 30)) / K_GAUSSIAN)
    assert "conformity" not in s["gamma_XB"]

    tight = _tolerances(tmp_path, "tight.toml", "alpha_XB_arcsec = 10\n")
    code, out, err = run_cli("sample", "--seed", "1", "--quiet", "--tolerances", tight)
    assert code == 0, err
    line = next(ln for ln in out.splitlines() if ln.startswith("alpha_XB") and "±10" in ln)
    p_nonconformance, verdict = line.split("″")[1].split(maxsplit=1)
    assert verdict == "does not conform" and float(p_nonconformance) > 0.999


@pytest.mark.parametrize("text, key", [
    ("alpha_XB_um = 3\n", "tolerances.alpha_XB_um"),
    ("nonsense_arcsec = 3\n", "tolerances.nonsense_arcsec"),
    ("alpha_XB_arcsec = -3\n", "tolerances.alpha_XB_arcsec"),
    ("alpha_XB_arcsec = {low = 5, high = 1}\n", "tolerances.alpha_XB_arcsec.high"),
    ("alpha_XB_arcsec = nan\n", "tolerances.alpha_XB_arcsec"),
    ("alpha_XB_arcsec = 3\nE_A0B_arcsec = 4\n", "tolerances.E_A0B_arcsec"),
])
def test_bad_tolerances_are_one_line(run_cli, tmp_path, text, key):
    f = _tolerances(tmp_path, "bad.toml", text)
    code, out, err = run_cli("sample", "--quiet", "--tolerances", f, "-o", str(tmp_path / "post.nc"))
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and f in err and key in err, err
    assert not (tmp_path / "post.nc").exists()


def test_campaign_tolerances_section_round_trips(tmp_path, thesis):
    from mtmcal_bayes.io.campaign_reader import load_campaign
    from mtmcal_bayes.io.campaign_writer import save_campaign

    thesis_copy = load_campaign()
    thesis_copy.tolerances = {"beta_CZ": Tolerance("beta_CZ", None, mb.units.to_internal(20.0, "arcsec"))}
    save_campaign(thesis_copy, tmp_path / "c.toml")
    back = load_campaign(tmp_path / "c.toml")
    assert back.tolerances["beta_CZ"].high == pytest.approx(thesis_copy.tolerances["beta_CZ"].high)
    assert back.tolerances["beta_CZ"].low is None


def test_dz_BT_rests_on_nuisance_priors(thesis_posterior):
    """dz_BT is confounded with the tool-length error: the Jacobian leaves it undetermined (``identified`` False,
    ``identification`` "not identified"), and the separate prior-sensitivity diagnostic names the dRB and zT priors
    its interval rests on (SPEC §20).  The eight of Table 4.5 are determined; the diagnostic names the T-ball
    centring priors where they rest on them, and that never changes their ``identified``."""
    s = thesis_posterior.summary
    assert s.loc["dz_BT", "identified_through"] == "dRB, zT"
    assert s.loc["dz_BT", "prior_sensitivity"] == "rests on the nuisance priors dRB and zT"
    assert s.loc["dz_BT", "nuisance_growth"] > 5
    assert s.loc["dz_BT", "identified"] is False and s.loc["dz_BT", "identification"] == "not identified"
    for n in EIGHT:
        assert s.loc[n, "identified"] is True and s.loc[n, "identification"] == "data", n
    assert s.loc["beta_XB", "prior_sensitivity"] == "rests on the nuisance prior xT"
    for n in ("alpha_CZ", "beta_CZ", "alpha_XB", "gamma_XB"):  # the data alone
        assert s.loc[n, "identified_through"] == "" and s.loc[n, "nuisance_growth"] < 1.05
    assert any(m.startswith("dz_BT: not identified by the data") for m in thesis_posterior.not_identified)
    msg = next(m for m in thesis_posterior.prior_notes if m.startswith("dz_BT"))
    assert "rests on the nuisance priors dRB" in msg and "zT" in msg


def test_json_summary_carries_the_gum_statement(thesis_posterior):
    s = thesis_posterior.to_json()["summary"]
    for name, e in s.items():
        assert e["iso"] == ISO_SYMBOL.get(name)
        assert e["u"] == pytest.approx(e["sd"], rel=1e-3)
        assert e["ci95_shortest"] == [pytest.approx(e["hdi_low"]), pytest.approx(e["hdi_high"])]
        lo, hi = e["ci95_symmetric"]
        assert lo < e["mean"] < hi and e["coverage_probability"] == 0.95
        assert (e["U"] is None) == (e["k"] is None) == bool(e["U_note"])
        if e["U"] is not None:
            assert e["U"] == pytest.approx(e["k"] * e["u"])
    assert s["dz_BT"]["identified_through"] == ["dRB", "zT"]


def test_console_shows_iso_symbols_and_statement(thesis_posterior):
    text = thesis_posterior.to_text()
    for name in EIGHT:
        row = next(ln for ln in text.splitlines() if ln.startswith(name + " "))
        if name in ISO_SYMBOL:
            assert ISO_SYMBOL[name] in row
    assert "Uncertainty statement (GUM-S1" in text


def test_marks_are_the_quantities_that_move_more_than_their_sd(thesis_posterior):
    """The built-in campaign's B runs were read by choice (docs/thesis-notes.md).  The quantities marked are those
    whose estimate moves by more than its sd between this posterior and the posterior of the campaign read in its
    recorded alternative (exact draws, the alternative built from the file's text), each with that estimate; on
    the console, in the GUM table and in the JSON."""
    alt = mb.sample(mb.parse_campaign(variants.alternative_reading()), seed=1, sampler="exact").summary
    s = thesis_posterior.summary
    moved = {n for n in alt.index if abs(alt.loc[n, "mean"] - s.loc[n, "mean"]) > s.loc[n, "sd"]}
    assert set(reading_choice.marked(s)) == moved and {"alpha_XB", "alpha_BT"} <= moved
    for n in moved:
        assert s.loc[n, "reading_alternative"] == pytest.approx(alt.loc[n, "mean"], abs=0.05 * s.loc[n, "sd"])
    text = thesis_posterior.to_text()
    for n in s.index:
        rows = [ln for ln in text.splitlines() if ln.startswith(n + " ")][:2]  # results table, GUM table
        assert len(rows) == 2 and all(ln.endswith(f"† {s.loc[n, 'reading_alternative']:.2f}") == (n in moved)
                                      for ln in rows), rows
    assert thesis_posterior.reading_choice_note in text and "BX@RB1/B read B0=+X,B90=-Z" in text
    j = thesis_posterior.to_json()
    assert set(j["reading_choice"]["rests_on_choice"]) == moved
    assert {n for n, e in j["summary"].items() if e["reading_choice"]["rests_on_choice"]} == moved


def test_without_the_record_of_the_choice_nothing_is_marked_and_no_number_moves(thesis_posterior):
    plain = mb.sample(mb.parse_campaign(variants.without_reading_choice()), seed=1)
    assert not reading_choice.has_choice(plain.summary) and plain.reading_choice_note == ""
    assert "†" not in plain.to_text() and "reading_choice" not in json.dumps(plain.to_json())
    pd.testing.assert_frame_equal(plain.summary, thesis_posterior.summary[plain.summary.columns])


def test_compensating_with_a_sampled_posterior_names_what_rests_on_the_choice(thesis_posterior, thesis, tmp_path):
    """From the NetCDF file (its attributes say which posterior it is): the deviations the posterior marks."""
    from mtmcal_bayes.datasets import data_path

    thesis_posterior.save(tmp_path / "post.nc")
    res = mb.compensate(data_path("fig4_30a_bx_original.nc"), campaign=thesis, posterior=tmp_path / "post.nc")
    used = set(res.info["deviations"])
    assert set(res.reading_choice["rests_on_choice"]) == used & set(reading_choice.marked(thesis_posterior.summary))
    assert {"alpha_XB", "alpha_BT"} <= set(res.reading_choice["rests_on_choice"])


def test_compensation_warns_about_prior_only_values(run_cli, tmp_path):
    from mtmcal_bayes.datasets import data_path

    code, out, err = run_cli("compensate", str(data_path("fig4_30a_bx_original.nc")), "-o", str(tmp_path / "c.nc"))
    assert code == 0
    lines = [ln for ln in err.splitlines() if "dz_BT" in ln]
    assert lines and all(ln.startswith("WARNING: ") for ln in lines)
    assert any("do not identify (the campaign's Jacobian leaves it undetermined" in ln for ln in lines)  # the rule
    assert any("rests on the nuisance priors dRB and zT" in ln for ln in lines)  # the separate diagnostic
    assert not any("alpha_XB" in ln for ln in err.splitlines())  # determined, resting on no nuisance prior


def test_report_carries_iso_gum_and_conformity(thesis_report):
    """The shared report (conftest.thesis_report_run) was made with E_B0B ±30″ and alpha_XB ±10″."""
    from .conftest import SHARED_REPORT_TOLERANCES

    assert "E_B0B_arcsec = 30\nalpha_XB_arcsec = 10\n" in SHARED_REPORT_TOLERANCES
    out_dir = thesis_report
    csv = pd.read_csv(out_dir / "summary.csv", index_col="quantity")
    for col in ("iso", "u", "ci95_shortest_low", "ci95_symmetric_high", "coverage_probability", "U", "k",
                "identified_through", "p_nonconformance", "conformity", "next_measurement"):
        assert col in csv.columns, col
    assert csv.loc["alpha_XB", "iso"] == "E_A0B" and csv.loc["alpha_XB", "conformity"] == "does not conform"
    assert csv.loc["beta_XB", "conformity"] == "undecided" and isinstance(csv.loc["beta_XB", "next_measurement"], str)
    html = (out_dir / "index.html").read_text()
    assert "Uncertainty statement" in html and "Conformity with the tolerances" in html
    for name, symbol in ISO_SYMBOL.items():
        if name in csv.index:
            assert symbol in html, symbol
