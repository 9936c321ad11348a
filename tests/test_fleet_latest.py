"""The fleet overview tells the history's answer: a machine's ``latest`` is its history's estimate at its latest
date (the single campaign's posterior beside it, one click away), conformity decided on what is shown, and the
machines × quantities table fits the page's 1180 px column.

The plant (built as ``tests/test_fleet.py`` builds its tree, seeded): P-1 with four campaigns and a 40″ step in
beta_XB before the third, P-2 with four campaigns and alpha_XB ramping by 8″ a year, P-3 with one campaign; every
campaign with its own ``[tolerances]`` beta_XB ±30″.  Exact posteriors (the linear model's): seconds.
"""

from __future__ import annotations

import datetime
import json
import re
from html.parser import HTMLParser

import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.campaign import Tolerance, Truth
from mtmcal_bayes.fleets.overview import OVERVIEW_QUANTITIES
from mtmcal_bayes.fleets.tolerances import estimate_conformity
from mtmcal_bayes.simulation.history import drift_from_display, synthetic_history

#: the keys of fleet.json before ``latest`` told the history's answer: scripts rely on them
TOP_KEYS = {"directory", "settings", "machines", "errors", "run", "files"}
SETTINGS_KEYS = {"model", "seed", "sampler", "target_ess", "max_steps", "version"}
MACHINE_KEYS = {"serial", "id", "page", "campaigns", "history", "changes", "forecast", "latest", "notes"}
CAMPAIGN_KEYS = {"file", "date", "temperature_C", "seed", "summary", "diagnostics", "warnings"}
HISTORY_KEYS = {"model", "dates", "files", "summary", "diagnostics"}
LATEST_KEYS = {"mean", "sd", "hdi_low", "hdi_high", "unit", "file", "date", "conformity", "p_nonconformance",
               "drift", "drift_date", "drift_probability", "recalibrate_by"}


@pytest.fixture(scope="module")
def plant(tmp_path_factory):
    root = tmp_path_factory.mktemp("plant") / "plant"
    base = mb.load_campaign()
    base.tolerances = {"beta_XB": Tolerance("beta_XB", units.to_internal(-30.0, "arcsec"),
                                            units.to_internal(30.0, "arcsec"), "tolerances.beta_XB_arcsec")}
    truth = Truth({"beta_XB": units.to_internal(-10.0, "arcsec")})
    dates = [datetime.datetime(2025, 1, 6) + datetime.timedelta(days=91 * i) for i in range(4)]
    step = drift_from_display("beta_XB", "step", 40.0, dates[2])
    ramp = drift_from_display("alpha_XB", "ramp", 8.0, dates[0])
    for serial, drifts, seed, n in (("P-1", [step], 21, 4), ("P-2", [ramp], 22, 4), ("P-3", [], 23, 1)):
        (root / serial).mkdir(parents=True)
        for c in synthetic_history(base, truth, dates[:n], drifts=drifts, serial=serial, seed=seed):
            c.machine.type = "MTX-200"  # one type: the fleet pools σ_model over P-1's and P-2's histories
            mb.save_campaign(c, root / serial / f"{c.date.date()}.toml")
    out = tmp_path_factory.mktemp("plant-out") / "overview"
    result = mb.fleet(root, workers=1, sampler="exact", output=out, cache=tmp_path_factory.mktemp("plant-cache"))
    assert result.exit_status == 0, result.errors
    return root, result, out


def test_latest_is_the_history_estimate_at_the_latest_date(plant):
    _, result, _ = plant
    for m in result.machines[:2]:
        history = m["history"]
        last = history["dates"][-1]
        assert last == m["campaigns"][-1]["date"] and history["files"][-1] == m["campaigns"][-1]["file"]
        now = history["summary"][last]
        for q in OVERVIEW_QUANTITIES:
            c, single = m["latest"][q], m["campaigns"][-1]["summary"][q]
            assert c["source"] == "history" and c["date"] == last and c["file"] == history["files"][-1]
            assert {k: c[k] for k in ("mean", "sd", "hdi_low", "hdi_high")} == now[q]
            # four campaigns know a quantity better than the latest one alone
            assert c["sd"] < single["sd"], (m["id"], q, c["sd"], single["sd"])
            assert c["campaign"] == {"file": m["campaigns"][-1]["file"], "date": last,
                                     **{k: single.get(k) for k in ("mean", "sd", "hdi_low", "hdi_high", "conformity",
                                                                   "p_nonconformance")},
                                     "page": f"machines/{m['id']}/campaigns.html#campaign-4"}
        # conformity decided on the estimate shown, against the campaigns' own ±30″
        b = m["latest"]["beta_XB"]
        assert b["tolerance"] == {"low": -30.0, "high": 30.0}
        assert (b["conformity"], b["p_nonconformance"]) == estimate_conformity(b["mean"], b["sd"], -30.0, 30.0)
        # quantities the history does not follow (not identified by the ball bar) stay the campaign's
        assert m["latest"]["sigma_model"]["source"] == "campaign"
    p1 = result.machines[0]
    assert p1["id"] == "P-1" and p1["latest"]["beta_XB"]["drift"]
    assert p1["latest"]["beta_XB"]["drift_date"] == p1["history"]["dates"][2]


def test_a_single_campaign_machine_shows_its_campaign(plant):
    _, result, _ = plant
    m = result.machines[2]
    assert m["id"] == "P-3" and m["history"] is None and len(m["campaigns"]) == 1
    own = m["campaigns"][0]
    for q, c in m["latest"].items():
        s = own["summary"][q]
        assert c["source"] == "campaign" and c["file"] == own["file"] and c["date"] == own["date"]
        assert (c["mean"], c["sd"], c["conformity"], c["p_nonconformance"]) == \
            (s["mean"], s["sd"], s.get("conformity"), s.get("p_nonconformance"))
        assert c["campaign"]["mean"] == s["mean"] and c["campaign"]["page"] == "machines/P-3/index.html#campaign-1"
    assert m["latest"]["beta_XB"]["conformity"] == own["summary"]["beta_XB"]["conformity"] is not None


def test_every_json_key_scripts_rely_on_is_still_there(plant):
    _, result, out = plant
    doc = json.loads((out / "fleet.json").read_text(encoding="utf-8"))
    assert TOP_KEYS <= set(doc) and SETTINGS_KEYS <= set(doc["settings"]) and doc["settings"]["tolerances"] is None
    for m in doc["machines"]:
        assert MACHINE_KEYS <= set(m)
        assert all(CAMPAIGN_KEYS <= set(c) for c in m["campaigns"])
        assert m["history"] is None or HISTORY_KEYS <= set(m["history"])
        assert all(LATEST_KEYS | {"source", "campaign", "tolerance"} <= set(c) for c in m["latest"].values())


class _Table(HTMLParser):
    """The overview's table: per row, per cell, its unbreakable pieces (text, small?) and its links."""

    def __init__(self):
        super().__init__()
        self.rows, self.inside, self.stack = [], False, []

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "table" and a.get("class") == "fleet":
            self.inside = True
        if not self.inside:
            return
        if tag == "tr":
            self.rows.append([])
        elif tag in ("td", "th"):
            self.rows[-1].append({"pieces": [], "links": [], "class": a.get("class") or ""})
        elif tag == "a":
            self.rows[-1][-1]["links"].append(a["href"])
        if tag not in ("br", "tr", "td", "th"):
            self.stack.append(a.get("class") or "")
        if tag in ("br", "span"):
            self.rows[-1][-1]["pieces"].append(["", tag == "span"])

    def handle_endtag(self, tag):
        if tag == "table":
            self.inside = False
        elif self.inside and tag not in ("br", "tr", "td", "th"):
            self.stack.pop()
            if tag == "span":
                self.rows[-1][-1]["pieces"].append(["", False])

    def handle_data(self, data):
        if self.inside and self.rows and self.rows[-1]:
            cell = self.rows[-1][-1]
            if not cell["pieces"]:
                cell["pieces"].append(["", False])
            cell["pieces"][-1][0] += data


def test_the_overview_fits_the_page_and_links_each_value_to_its_campaign(plant):
    _, result, out = plant
    page = (out / "index.html").read_text(encoding="utf-8")
    table = _Table()
    table.feed(page)
    head, *rows = table.rows
    assert len(head) == 2 + len(OVERVIEW_QUANTITIES) and len(rows) == 3
    assert [re.sub(r"<[^>]+>", "", h) for h in re.findall(r'<th class="q"[^>]*>(.*?)</th>', page)] == \
        ["αCZ", "βCZ", "αXB", "βXB", "γXB", "αBT", "δxCZ−δxBT", "δyCZ"]
    # characters per row: the widest unbreakable piece of each column (small text counts 0.8), summed
    widest = [0.0] * len(head)
    for row in rows:
        assert len(row) == len(head)
        for i, cell in enumerate(row):
            for text, small in cell["pieces"]:
                widest[i] = max(widest[i], len(text.strip()) * (0.8 if small else 1.0))
    assert max(widest[1:-1]) <= 16, widest  # one short line per value: "-26.5 ± 3.4″", "0.3 ± 1.7 µm"
    assert sum(widest) <= 140, widest  # ≈ 1180 px at 13.8 px type, about 8 px a character
    # each value links to the latest campaign's own section on the machine's page, which exists
    for m, row in zip(result.machines, rows):
        for q, cell in zip(OVERVIEW_QUANTITIES, row[1:-1]):
            assert cell["links"] == [m["latest"][q]["campaign"]["page"]]
            target, anchor = cell["links"][0].split("#")
            assert f'id="{anchor}"' in (out / target).read_text(encoding="utf-8")
    assert "Φ((low − mean)/sd)" in page and "latest campaign alone" in page


def test_the_summary_csv_shows_the_history_estimate_and_its_source(plant):
    import pandas as pd

    _, result, out = plant
    csv = pd.read_csv(out / "fleet_summary.csv")
    p1 = csv[(csv.machine == "P-1") & (csv.quantity == "alpha_CZ")].iloc[0]
    latest = result.machines[0]["latest"]["alpha_CZ"]
    assert p1["source"] == "history" and p1["mean"] == pytest.approx(latest["mean"], rel=1e-12)
    assert p1["campaign_sd"] == pytest.approx(latest["campaign"]["sd"], rel=1e-12) and p1["campaign_sd"] > p1["sd"]
    assert set(csv[csv.machine == "P-3"]["source"]) == {"campaign"}


def test_the_type_pools_sigma_model_and_teaches_the_single_campaign_machine(plant):
    """P-1, P-2 and P-3 are one type: the fleet pools σ_model over the two histories (the simulated campaigns have
    no discrepancy beyond the instrument, so the pooled scale is small), every machine of the type carries it, the
    prior file is written, and P-3's single campaign sampled with it (``sample --sigma-model-prior``) has a narrower
    alpha_CZ interval than under the assumed prior, its budget naming the fleet as the source."""
    root, result, out = plant
    pooled = result.types["MTX-200"]
    assert pooled["machines"] == 3 and pooled["histories"] == 2
    assert pooled["median_um"] < 1.0, pooled
    assert all(m["sigma_model"] == pooled for m in result.machines)
    doc = json.loads((out / "fleet.json").read_text())
    assert doc["sigma_model_types"]["MTX-200"]["prior_file"] == pooled["prior_file"]
    prior_file = out / pooled["prior_file"]
    single = next(root.glob("P-3/*.toml"))
    learnt = mb.sample(single, sampler="exact", seed=1, sigma_model_prior=prior_file)
    assumed = mb.sample(single, sampler="exact", seed=1)
    sd_l, sd_a = learnt.summary.loc["alpha_CZ", "sd"], assumed.summary.loc["alpha_CZ", "sd"]
    assert sd_l < 0.8 * sd_a, (sd_l, sd_a)
    assert "learnt elsewhere" in learnt.to_text() and str(root) in learnt.to_text()
