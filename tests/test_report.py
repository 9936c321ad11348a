"""The HTML report: files, self-containedness, captions, missing data, atomic output, model comparison."""

import re
from html import unescape

import numpy as np
import pandas as pd
import pytest
from matplotlib.image import imread

from mtmcal_bayes import identify, load_campaign
from mtmcal_bayes.models import models_of
from mtmcal_bayes.figure_style import save_png
from mtmcal_bayes.parameters import IDENTIFIABLE
from mtmcal_bayes.reporting import build as report_build
from mtmcal_bayes.reporting.corner_plot import corner_figure

from . import variants

REQUIRED = ["index.html", "corner.png", "forest.png", "ppc.png", "polar.png", "widths.png", "rank.png", "trace.png",
            "summary.csv", "ppc.csv", "diagnostics.csv", "priors.csv", "identification_ballbar.csv", "posterior.nc"]
QUICK = ("--seed", "2", "--quiet")  # the default run: converged in seconds


# the report of the built-in campaign every test here reads: conftest.thesis_report_run (one per session)


def test_report_writes_every_file(thesis_report):
    for name in REQUIRED:
        assert (thesis_report / name).is_file(), name
    for png in thesis_report.glob("*.png"):
        img = imread(png)
        assert img.shape[0] > 300 and img.shape[1] > 300, png.name


def test_summary_csv_columns_and_reference_values(thesis_report, thesis):
    s = pd.read_csv(thesis_report / "summary.csv", index_col="quantity")
    for col in ("mean", "sd", "median", "hdi_low", "hdi_high", "r_hat", "ess_bulk", "ballbar", "ballbar_in_hdi",
                "probe_reported", "probe_reported_in_hdi", "probe_recomputed", "probe_recomputed_in_hdi"):
        assert col in s.columns, col
    ident = identify(thesis)  # the deterministic values of the data the posterior saw: the campaign's reading
    for name, value in ident.ballbar_in_convention.items():
        assert s.loc[name, "ballbar"] == pytest.approx(value.display, abs=1e-4)
        inside = s.loc[name, "hdi_low"] <= s.loc[name, "ballbar"] <= s.loc[name, "hdi_high"]
        assert bool(s.loc[name, "ballbar_in_hdi"]) == inside
    assert s.loc["beta_XB", "probe_reported"] == pytest.approx(-19.04)
    assert np.isnan(s.loc["alpha_BT", "probe_reported"])  # the probe gives no alpha_BT


def test_html_is_self_contained_with_captions(thesis_report):
    html = unescape((thesis_report / "index.html").read_text(encoding="utf-8"))
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:|//|file:)""", html)
    assert "<link" not in html and "<script" not in html
    pngs = sorted(p.name for p in thesis_report.glob("*.png"))
    imgs = re.findall(r'<img src="data:image/png;base64,[A-Za-z0-9+/=]+"', html)
    assert len(imgs) == len(pngs)
    for name in pngs:
        assert f"<strong>{name}.</strong>" in html  # each figure has its caption
    assert "68 %" in html and "95 %" in html and "corner's default" in html
    text = re.sub(r"<img[^>]*>", "", html)
    assert not re.search(r"\bnan\b", text, re.IGNORECASE)
    assert "converged by the rule" in html and "NOT converged" not in html
    assert "against the exact σ-marginal posterior: means within" in html  # the accuracy check


def test_unconverged_report_says_so(run_cli, tmp_path):
    """The smallest step budget (the first check's, 50 steps) and an ESS target no run meets."""
    code, _out, err = run_cli("report", "-o", tmp_path / "rep", "--max-steps", "50", "--target-ess", "1e6",
                              "--seed", "2", "--quiet")
    assert code == 0, err
    html = unescape((tmp_path / "rep" / "index.html").read_text(encoding="utf-8"))
    assert "step budget of 50 reached" in html and "NOT converged" in html
    assert "WARNING: step budget of 50 reached" in err


@pytest.fixture(scope="module")
def thesis_corner(thesis_report):
    """``(idata, summary, figure, off)``: the corner figure of the shared report's posterior, drawn again here
    (:func:`corner_figure`) once for the two tests that read it; neither changes it (drawing it to pixels does
    not)."""
    import arviz as az

    idata = az.from_netcdf(thesis_report / "posterior.nc")
    comp = pd.read_csv(thesis_report / "summary.csv", index_col="quantity")
    fig, off = corner_figure(idata, comp, IDENTIFIABLE)
    return idata, comp, fig, off


def test_corner_lists_reference_values_it_cannot_draw(thesis_corner, tmp_path):
    _, _, fig, off = thesis_corner
    save_png(fig, tmp_path / "corner_again.png")  # not into the shared report, which other tests list
    # the recomputed probe gamma_XB (about −91″, Eq 5.17 with assumed nominals) is tens of sd away
    assert any(o.startswith("gamma_XB: touch probe, recomputed") for o in off)
    assert not any(o.startswith("beta_XB") for o in off)


def test_corner_leaves_out_only_the_draws_its_fill_hides(thesis_corner, monkeypatch):
    """The corner plot draws only the draws not under corner's opaque fill of the densest region (a twentieth of
    them); drawn with every draw instead, the PNG is the same, pixel for pixel."""
    from mtmcal_bayes.figure_style import _canvas_rgb, png_dpi
    from mtmcal_bayes.reporting import corner_plot

    idata, comp, fig, _ = thesis_corner
    lines = [ln for ax in fig.axes for ln in ax.lines if ln.get_marker() == "o" and ln.get_alpha() == 0.02]
    shown = sum(len(ln.get_xdata()) for ln in lines)
    n = len(corner_plot._draws(idata, list(IDENTIFIABLE)))
    assert len(lines) == 28 and 0 < shown < 0.2 * 28 * n
    monkeypatch.setattr(corner_plot, "_shown_draws", lambda ax, xy: xy)
    every, _ = corner_figure(idata, comp, IDENTIFIABLE)
    np.testing.assert_array_equal(_canvas_rgb(fig, png_dpi(fig)), _canvas_rgb(every, png_dpi(every)))


def test_report_on_both_instruments_draws_the_ball_bar_posteriors_eccentricity_plots(run_cli, tmp_path):
    """``report --data both``: the main posterior is the fused one, and the eccentricity plots (predictive check,
    polar trajectories) are its own, as they are of any main posterior that saw the ball bar (on every machine);
    the ball-bar-only and probe-only side posteriors are shown by their intervals."""
    code, out, err = run_cli("report", "--data", "both", "-o", tmp_path / "rep", *QUICK)
    assert code == 0, err
    ppc_table = pd.read_csv(tmp_path / "rep" / "ppc.csv")
    assert len(ppc_table) and ppc_table.notna().all().all()
    for name in ("ppc.png", "polar.png", "instruments_forest.png"):
        assert (tmp_path / "rep" / name).stat().st_size > 10_000
    intervals = pd.read_csv(tmp_path / "rep" / "instruments.csv")
    assert set(intervals["data"]) == {"ball bar only", "probe only", "fused"}
    # the fused posterior's marks of the B runs' choice of reading: α_XB and γ_XB trade places, dy_CZ follows ez_BY
    s = pd.read_csv(tmp_path / "rep" / "summary.csv", index_col="quantity")
    assert {"alpha_XB", "gamma_XB", "dy_CZ"} <= set(s.index[s["rests_on_reading"]])
    assert (s["rests_on_reading"] == (abs(s["reading_shift_sd"]) > 1)).all()


# a report of a campaign without touch-probe data: tests/test_formats.py (the first simulate's campaign of the corpus)


def test_report_without_second_tool_length_says_what_is_missing(run_cli, tmp_path):
    src = tmp_path / "no_cr2.toml"
    src.write_text(variants.without_second_tool_length(), encoding="utf-8")
    code, out, err = run_cli("report", src, "-o", tmp_path / "rep", *QUICK)
    assert code == 0, err
    html = unescape((tmp_path / "rep" / "index.html").read_text(encoding="utf-8"))
    assert "needs ey of CR at a second tool length (R'_B)" in html
    assert "alpha_BT: determined only in combination: dy_CZ" in html  # the Jacobian: dy_CZ − Z_T·alpha_BT only
    s = pd.read_csv(tmp_path / "rep" / "summary.csv", index_col="quantity")
    assert not s.loc["alpha_BT", "identified"] and np.isnan(s.loc["alpha_BT", "ballbar"])
    # the plan begun before the sampling (for all eight) is replaced by one for what the data do not determine one
    # by one, and its figures are drawn from that one
    unidentified = {n for n in IDENTIFIABLE if s.loc[n, "identification"] != "data"}
    assert {"alpha_BT", "dy_CZ"} <= unidentified
    planned = pd.read_csv(tmp_path / "rep" / "plan.csv")
    assert {c[: -len(" sd_after")] for c in planned.columns if c.endswith(" sd_after")} == unidentified
    assert all((tmp_path / "rep" / f).stat().st_size > 0 and f in out for f in ("plan_sweep.png", "plan_ranking.png"))
    assert f"Targets: {', '.join(n for n in IDENTIFIABLE if n in unidentified)}" in html


def test_bad_input_writes_nothing(run_cli, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[machine\n", encoding="utf-8")
    code, out, err = run_cli("report", bad, "-o", tmp_path / "rep")
    assert code == 2 and len(err.strip().splitlines()) == 1 and "bad.toml" in err
    assert not (tmp_path / "rep").exists()
    (tmp_path / "afile").write_text("x")
    code, out, err = run_cli("report", "-o", tmp_path / "afile", *QUICK)
    assert code == 2 and "not a directory" in err
    code, out, err = run_cli("report", "-o", tmp_path / "missing" / "rep", *QUICK)
    assert code == 2 and "does not exist" in err


def test_failure_midway_leaves_nothing_half_written(run_cli, tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("simulated failure while drawing")

    monkeypatch.setattr(report_build.polar, "polar_figure", broken)
    existing = tmp_path / "rep"
    existing.mkdir()
    (existing / "keep.txt").write_text("mine")
    code, out, err = run_cli("report", "-o", existing, *QUICK)
    assert code == 1 and "simulated failure" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["rep"]  # no temporary directory left
    assert sorted(p.name for p in existing.iterdir()) == ["keep.txt"]


def test_compare_models(thesis_report):
    """The shared report was made with --compare-models."""
    rep = thesis_report
    for name in ("compare_forest.png", "compare_ppc.png", "compare_models.csv", "compare_fit.csv"):
        assert (rep / name).is_file(), name
    table = pd.read_csv(rep / "compare_models.csv")
    models = models_of(load_campaign().machine)  # the thesis machine's: its three and the chain
    assert sorted(table["model"].unique()) == sorted(models) and len(models) == 4
    assert len(table) == 4 * 8
    # the literal kinematic model reads alpha_BT very differently from the thesis relations (SPEC §3.2)
    m = table.set_index(["quantity", "model"])["mean"]
    assert abs(m["alpha_BT", "htm-literal"] - m["alpha_BT", "linear"]) > abs(m["alpha_BT", "htm-thesis"] - m["alpha_BT", "linear"])
    html = unescape((rep / "index.html").read_text(encoding="utf-8"))
    assert "Model comparison" in html
    # beta_XB: about −35″ under the thesis relations, +38″ under the literal Eq 2.10 (sd ≈ 12″ each)
    assert "beta_XB: linear" in html and "htm-literal" in html.split("beta_XB: linear")[1][:80]


def test_report_json(thesis_report_run):
    import json

    data = json.loads(thesis_report_run[1])
    assert data["files"][0] == "index.html" and "summary.csv" in data["files"]
    assert set(data["summary"]["beta_XB"]) >= {"mean", "sd", "median", "hdi_low", "hdi_high", "r_hat", "ess_bulk",
                                               "ess_tail", "unit"}
    assert data["summary"]["beta_XB"]["unit"] == "arcsec" and data["missing"] == []


def test_the_marks_of_the_choice_of_reading_render(thesis_report_run):
    """The built-in campaign's B runs were read by choice: the results table and the uncertainty statement of
    index.html mark exactly the quantities summary.csv and the JSON say rest on it, each with its value under the
    best rejected reading, and say in one line what the mark means."""
    import json

    out, stdout = thesis_report_run
    s = pd.read_csv(out / "summary.csv", index_col="quantity")
    marked = set(s.index[s["rests_on_reading"]])
    assert {"alpha_XB", "alpha_BT"} <= marked and (s["rests_on_reading"] == (abs(s["reading_shift_sd"]) > 1)).all()
    assert set(json.loads(stdout)["reading_choice"]["rests_on_choice"]) == marked
    html = unescape((out / "index.html").read_text(encoding="utf-8"))
    for section in ("results", "statement"):
        part = html[html.index(f'id="{section}"'):]
        table = part[part.index("<table>"): part.index("</table>")]
        heads = re.findall(r"<th>(.*?)</th>", table[: table.index("</thead>")])
        col = heads.index("rejected reading")
        cells = {r[0]: r[col] for r in (re.findall(r"<td[^>]*>(.*?)</td>", row)
                                         for row in table.split("<tr>")[2:])}
        assert {n for n, c in cells.items() if c} == marked
        for n in marked:
            assert cells[n] == f"† {s.loc[n, 'reading_alternative']:.2f}"
    assert "† rests on the reading chosen for BX@RB1/B, BY@RB1/B: under the best rejected reading" in html
    certificate = html[html.index("(alpha_XB) = "):].split("</li>")[0]
    assert "† Under the best rejected reading of the ball-bar runs the estimate would be" in certificate


def test_the_weighing_begun_before_the_sampling_is_dropped_when_nothing_needs_explaining(thesis, thesis_report,
                                                                                         tmp_path, monkeypatch):
    """The built-in campaign's instruments agree; read as the thesis reads it (patched here) nothing is left to
    explain: the weighing, begun beside the sampling only for a campaign read otherwise (else only when the
    comparison finds a conflict), is not made and the report has no explanations table, while the built-in reading
    (the shared report) keeps it."""
    assert (thesis_report / "explanations.csv").exists()
    monkeypatch.setattr(report_build, "reads_as_thesis", lambda ballbar: True)
    dropped = report_build.build_report(thesis, tmp_path / "dropped", settings=report_build.SamplerSettings(seed=2))
    assert "explanations.csv" not in dropped.files and not (tmp_path / "dropped" / "explanations.csv").exists()
    assert "instruments.csv" in dropped.files and "plan_sweep.png" in dropped.files
    html = (tmp_path / "dropped" / "index.html").read_text(encoding="utf-8")
    assert "Where a conflict could come from" not in html
