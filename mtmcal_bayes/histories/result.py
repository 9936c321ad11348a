"""The result of ``history``: every quantity at every date, the flagged changes, the forecast; text, JSON, files."""

from __future__ import annotations

import datetime
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd

from .. import units
from ..arviz_import import az
from ..figure_style import save_png
from ..html_page import Page
from ..io.json_text import json_text
from ..io.textfiles import atomic_directory
from ..iso import iso_symbol
from ..parameters import quantity_unit, weights
from .fit import ALPHA, FORECAST_RISK, HORIZON_YEARS, IDENTIFIED_SD_RATIO, TREND_BAYES_FACTOR, HistoryFit


def _iso(d: datetime.datetime) -> str:
    return d.date().isoformat() if d.time() == datetime.time() else d.isoformat()


@dataclass
class HistoryResult:
    """One machine's history.

    ``summary``: rows (date, quantity) with mean, sd, hdi_low, hdi_high (display units; the 95 % interval of
    the mixture posterior); ``changes``: every (quantity, interval) with its probability of a change larger
    than the threshold, ``flagged`` where it passes the Bonferroni level; ``forecast``: per toleranced
    quantity its "recalibrate by" date (None when beyond the horizon).
    """

    serial: str
    dates: list[datetime.datetime]
    files: list[str]
    summary: pd.DataFrame
    changes: list[dict]
    forecast: list[dict]
    fit: HistoryFit
    tolerances: dict = field(default_factory=dict)  # {name: (low, high)} display units, ±inf when open
    output: str | None = None
    written: list[str] = field(default_factory=list)
    model: str = "linear"
    linearisation: dict | None = None  # a kinematic model's check of its expansion (.kinematic)
    temperatures: list[float] | None = None  # °C per campaign, when the thermal sensitivities were modelled
    summary_20C: pd.DataFrame | None = None  # as ``summary``, at 20 °C (when the temperatures were modelled)
    machine: dict = field(default_factory=dict)  # {"type", "configuration", "description"} of the latest campaign
    #: a described machine's deviations the campaigns do not determine one by one: ``[{"quantity", "why"}]``
    not_determined: list[dict] = field(default_factory=list)
    #: toleranced quantities without a forecast, with why: ``[{"quantity", "key", "why"}]``
    no_forecast: list[dict] = field(default_factory=list)

    @property
    def summary_at_20C(self) -> pd.DataFrame:
        """The summary referred to 20 °C (the summary itself when no temperatures were modelled)."""
        return self.summary if self.summary_20C is None else self.summary_20C

    def trend(self) -> dict:
        """Per quantity: ``model`` ("trend" where a deviation it is made of has a kept drift rate, else
        "random-walk"), the rate's posterior mean and sd per year (0 for a random walk) and its unit."""
        kept = set(self.fit.trend.get("trended", []))
        out = {}
        for k, q in enumerate(self.fit.quantities):
            uses = {n for n, w in weights(q, self.fit.model.deviations).items() if w}
            m, v = self.fit.rate_mean[:, k], self.fit.rate_var[:, k]
            out[q] = {"model": "trend" if uses & kept else "random-walk", "rate_mean": float(m.mean()),
                      "rate_sd": float(np.sqrt(v.mean() + m.var())), "unit": f"{units.SYMBOL[quantity_unit(q)]}/year",
                      "log10_bayes_factor": max((self.fit.trend[n] for n in uses if n in self.fit.trend), default=None)}
        return out

    def sigma_model(self) -> dict:
        """What the history taught of σ_model (shared by its campaigns): median, mean and sd of ln(σ/µm), and the
        prior it was learnt under, of its first discrepancy scale (the ball bar's where its data have it); where the
        data use other instruments, ``scale`` names it and ``scales`` gives each instrument's the same way."""
        hm = self.fit.model
        s2 = self.fit.s2.reshape(len(self.fit.s2), -1)
        each = {}
        for i, (name, prior) in enumerate(zip(hm.scales, hm.sigma_priors)):
            u = np.log(units.from_internal(np.sqrt(s2[:, i]), "um"))
            each[name] = {"median_um": float(np.exp(np.median(u))), "mean_log_um": float(u.mean()),
                          "sd_log": float(u.std()),
                          "prior": f"{prior.dist}, sd {units.from_internal(prior.sd, 'um'):.3g} µm"}
        first = each[hm.scales[0]]
        if hm.scales == ("sigma_model",):
            return first
        return {**first, "scale": hm.scales[0], "scales": each}

    def thermal(self) -> dict:
        """Per quantity: the thermal sensitivity's posterior mean and sd per °C, its unit, and ``identified``
        (false where its posterior sd is not below :data:`~.fit.IDENTIFIED_SD_RATIO` of the prior's: the prior sets
        it); empty without temperatures."""
        if self.temperatures is None:
            return {}
        out = {}
        for k, q in enumerate(self.fit.quantities):
            m, v = self.fit.thermal_mean[:, k], self.fit.thermal_var[:, k]
            sd = float(np.sqrt(v.mean() + m.var()))
            prior = float(self.fit.thermal_prior_sd[k])
            out[q] = {"mean": float(m.mean()), "sd": sd, "prior_sd": prior,
                      "unit": f"{units.SYMBOL[quantity_unit(q)]}/°C", "identified": bool(sd < IDENTIFIED_SD_RATIO * prior)}
        return out

    @property
    def flagged(self) -> list[dict]:
        return [c for c in self.changes if c["flagged"]]

    def to_json(self) -> dict:
        """The interface of ``history --json`` (docs/history.md)."""
        def nested(frame):
            out = {}
            for (when, q), r in frame.iterrows():
                out.setdefault(when, {})[q] = {c: float(r[c]) for c in ("mean", "sd", "hdi_low", "hdi_high")}
            return out

        extra = {}
        if self.temperatures is not None:
            extra = {"summary_20C": nested(self.summary_20C),
                     "temperatures_C": self.temperatures}
        return {
            "serial": self.serial, "machine": self.machine, "dates": [_iso(d) for d in self.dates], "files": self.files,
            "summary": nested(self.summary), **extra, "model": self.model,
            "trend": self.trend(), "thermal": self.thermal(), "sigma_model": self.sigma_model(),
            "linearisation": self.linearisation, "not_determined": self.not_determined,
            "changes": [{"quantity": c["quantity"], "date": _iso(c["date"]), "probability": c["probability"],
                         "delta": c["delta"], "threshold": c["threshold"]} for c in self.flagged],
            "forecast": [{"quantity": f["quantity"], "recalibrate_by": f["recalibrate_by"] and _iso(f["recalibrate_by"]),
                          "tolerance": f["tolerance"]} for f in self.forecast],
            **({"no_forecast": self.no_forecast} if self.no_forecast else {}),
            "diagnostics": {"acceptance": self.fit.acceptance, "tau_max_steps": self.fit.tau_max,
                            "false_alarm_rate": ALPHA, "flag_level": self.changes[0]["level"] if self.changes else None},
            "output": self.output,
        }

    def to_text(self) -> str:
        kept = self.fit.trend.get("trended", [])
        drift = "random walks" + (f", a drift rate for {', '.join(kept)}" if kept else "")
        lines = [f"History of machine {self.serial or '(no serial)'}: {len(self.dates)} campaigns, "
                 f"{_iso(self.dates[0])} to {_iso(self.dates[-1])} ({drift}; {self.model} model"
                 + (", thermal sensitivities modelled, results at 20 °C" if self.temperatures is not None else "")
                 + ")"]
        if self.linearisation is not None:
            c = self.linearisation
            lines.append(f"Linearised at the history's estimate; the {c['model']} model differs from its expansion by up "
                         f"to {c['max_gap_um']:.3f} µm (instrument accuracy {c['accuracy_um']:g} µm)"
                         + ("" if c["ok"] else ": WARNING, more than the accuracy — the deviations are large for a "
                            "linearised history"))
        if self.machine.get("description") not in (None, "thesis"):
            lines.append(f"Machine type {self.machine.get('type') or '(none)'}, {self.machine.get('configuration')} "
                         f"({self.machine.get('description')}); its own deviations (ISO 230-7)")
        last = self.dates[-1]
        where = " (at 20 °C)" if self.temperatures is not None else ""
        lines.append(f"{'quantity':18s} {'ISO':10s} {'unit':>4s} {'first' + where:>16s} {'last' + where:>16s}")
        table = self.summary_at_20C
        for q in self.fit.quantities:
            a, b = table.loc[(_iso(self.dates[0]), q)], table.loc[(_iso(last), q)]
            lines.append(f"{q:18s} {iso_symbol(q) or (q if q.startswith('E_') else '—'):10s} {units.SYMBOL[quantity_unit(q)]:>4s} "
                         f"{a['mean']:8.2f} ± {a['sd']:5.2f} {b['mean']:8.2f} ± {b['sd']:5.2f}")
        lines += [f"{n['quantity']:18s} not shown as measured: {n['why']}" for n in self.not_determined]
        level = self.changes[0]["level"] if self.changes else 1.0
        lines += ["", f"Changes flagged (P(|Δ| > threshold) > {level:.4f}: family-wise false-alarm rate ≤ "
                  f"{100 * ALPHA:g} % over {len(self.changes)} quantity × interval pairs):"]
        lines += [f"  {c['quantity']} before {_iso(c['date'])}: Δ = {c['delta']:+.2f} "
                  f"{units.SYMBOL[quantity_unit(c['quantity'])]}, P(|Δ| > {c['threshold']:g}) = {c['probability']:.4f}"
                  for c in self.flagged] or ["  none"]
        trend = self.trend()
        rows = [f"  {q:18s} {t['rate_mean']:+7.2f} ± {t['rate_sd']:5.2f} {t['unit']}" for q, t in trend.items()
                if t["model"] == "trend"]
        lines += ["", "Drift rates kept (Bayes factor of a trend against the random walk ≥ "
                  f"{TREND_BAYES_FACTOR:g}):"] + (rows or ["  none: every quantity drifts as a random walk"])
        if self.temperatures is not None:
            lines += ["", "Thermal sensitivities (measured = at 20 °C + sensitivity × (temperature − 20 °C)):"]
            lines += [f"  {q:18s} {t['mean']:+7.2f} ± {t['sd']:5.2f} {t['unit']}"
                      + ("" if t["identified"] else f"  prior only (prior sd {t['prior_sd']:g})")
                      for q, t in self.thermal().items()]
        if self.forecast or self.no_forecast:
            lines += ["", f"Forecast: the date by which P(out of tolerance) passes {100 * FORECAST_RISK:g} % "
                      f"(horizon {HORIZON_YEARS:g} years):"]
            lines += [f"  {f['quantity']} (tolerance {f['tolerance']}): "
                      f"{_iso(f['recalibrate_by']) if f['recalibrate_by'] else 'beyond the horizon'}" for f in self.forecast]
        lines += [f"  {f['quantity']} ({f['key'] or 'tolerance'}): {f['why']}" for f in self.no_forecast]
        if self.output:
            lines += ["", f"written to {self.output}/: {', '.join(self.written)}"]
        return "\n".join(lines)

    def write(self, out_dir) -> list[str]:
        """history.json, history_summary.csv, changes.csv, forecast.csv, trend.png and index.html into ``out_dir``
        (atomically)."""
        from .figures import trend_figure

        out_dir = Path(out_dir)
        files = ["index.html", "history.json", "history_summary.csv", "changes.csv", "forecast.csv", "trend.csv",
                 "trend.png"] + (["history_summary_20C.csv", "thermal.csv"] if self.temperatures is not None else [])
        with atomic_directory(out_dir) as tmp:
            self.output = str(out_dir)
            self.written = files
            (tmp / "history.json").write_text(json_text(self.to_json()) + "\n", encoding="utf-8")
            self.summary.to_csv(tmp / "history_summary.csv", float_format="%.6g")
            pd.DataFrame(self.trend()).T.rename_axis("quantity").to_csv(tmp / "trend.csv", float_format="%.6g")
            if self.temperatures is not None:
                self.summary_20C.to_csv(tmp / "history_summary_20C.csv", float_format="%.6g")
                pd.DataFrame(self.thermal()).T.rename_axis("quantity").to_csv(tmp / "thermal.csv", float_format="%.6g")
            pd.DataFrame(self.changes).to_csv(tmp / "changes.csv", index=False, float_format="%.6g")
            pd.DataFrame(self.forecast).to_csv(tmp / "forecast.csv", index=False)
            save_png(trend_figure(self), tmp / "trend.png")
            self._page(tmp).write(tmp / "index.html", f"Machine {self.serial} · {len(self.dates)} campaigns · "
                                  f"mtmcal-bayes history")
        return files

    def _page(self, tmp: Path) -> Page:
        page = Page(f"Calibration history — machine {self.serial or '(no serial)'}")
        flagged = [f"{c['quantity']}: changed by {c['delta']:+.1f} {units.SYMBOL[quantity_unit(c['quantity'])]} before "
                   f"{_iso(c['date'])} (P(|Δ| > {c['threshold']:g}) = {c['probability']:.4f})" for c in self.flagged]
        page.box("warn", "Changes flagged", flagged)
        page.section("trend", "Every quantity at every date")
        page.paragraph("Posterior mean and 95 % band of each quantity at each campaign, from all campaigns jointly "
                       "(deviations as Gaussian random walks in time, each campaign with its own set-up offsets; "
                       "docs/history.md). Dashed: the forecast band after the last campaign; red: tolerances.")
        page.figure(tmp / "trend.png", "Trend of each quantity with 95 % bands and the forecast.", "trends")
        wide = self.summary_at_20C.reset_index().pivot(index="date", columns="quantity", values="mean")
        page.table(wide[[q for q in self.fit.quantities if q in wide.columns]], digits=2)
        if self.not_determined:
            page.paragraph(f"Machine configuration {self.machine.get('configuration')}: deviations its campaigns do not "
                           "determine one by one are in the model (integrated with their priors) but not shown as "
                           "measured:")
            page.table(pd.DataFrame(self.not_determined), index=False)
        page.section("drift", "Drift: random walk or trend")
        page.paragraph(f"Each deviation drifts as a random walk; a drift rate is added where the Bayes factor of "
                       f"\"random walk + trend\" against the random walk alone reaches {TREND_BAYES_FACTOR:g} (the "
                       "rate's prior costs an Occam factor, so a flat quantity stays flat). The forecast extrapolates "
                       "a kept rate with its uncertainty. Rates per year:")
        page.table(pd.DataFrame(self.trend()).T.rename_axis("quantity"), digits=3)
        if self.temperatures is not None:
            page.section("thermal", "Temperature")
            page.paragraph("Each campaign measured at its workshop temperature; the quantities above are referred to "
                           "20 °C (ISO 1), the values as measured = at 20 °C + sensitivity × (temperature − 20 °C). "
                           "A sensitivity whose posterior sd is not below half its prior sd is the prior's, not the "
                           "machine's (identified = false).")
            page.table(pd.DataFrame(self.thermal()).T.rename_axis("quantity"), digits=3)
        if self.linearisation is not None:
            c = self.linearisation
            page.paragraph(f"Kinematic model {c['model']}: {c['points']}; the model differs from its expansion by up to "
                           f"{c['max_gap_um']:.3f} µm over the posterior (instrument accuracy {c['accuracy_um']:g} µm).")
        page.section("changes", "Changes between campaigns")
        page.paragraph(f"P(|Δ| > threshold) for each quantity between consecutive campaigns; flagged above "
                       f"{self.changes[0]['level']:.4f} = 1 − {ALPHA:g}/K (Bonferroni over the K = {len(self.changes)} "
                       "pairs): with no change, a flag anywhere in the history has probability ≤ 5 %." if self.changes
                       else "One interval only.")
        table = pd.DataFrame(self.changes).drop(columns=["level"])
        page.table(table.assign(date=table["date"].map(_iso)) if len(table) else table, digits=4, index=False)
        if self.forecast:
            page.section("forecast", "Forecast")
            page.table(pd.DataFrame(self.forecast), index=False)
        return page


def summary_frame(hf: HistoryFit, dates, *, at_20C: bool = False) -> pd.DataFrame:
    """Rows (date, quantity): mean, sd and the 95 % HDI of the mixture posterior (display units; the HDI from 50
    draws per scale draw), as measured (at each campaign's temperature) or ``at_20C``."""
    rng = np.random.default_rng(0)
    rows = {}
    mean, sd = (hf.mean, hf.sd) if at_20C else (hf.measured_mean, hf.measured_sd)
    for t, when in enumerate(dates):
        for k, q in enumerate(hf.quantities):
            m, s = mean[:, t, k], sd[:, t, k]
            draws = (m[:, None] + s[:, None] * rng.standard_normal((len(m), 50))).ravel()
            lo, hi = az.hdi(draws, hdi_prob=0.95)
            rows[(_iso(when), q)] = {"mean": float(m.mean()), "sd": float(np.sqrt(np.mean(s**2) + np.var(m))),
                                           "hdi_low": float(lo), "hdi_high": float(hi)}
    df = pd.DataFrame.from_dict(rows, orient="index")
    df.index = pd.MultiIndex.from_tuples(df.index, names=["date", "quantity"])
    return df
