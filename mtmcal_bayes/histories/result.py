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
from ..parameters import quantity_unit
from .fit import ALPHA, FORECAST_RISK, HORIZON_YEARS, HistoryFit


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

    @property
    def flagged(self) -> list[dict]:
        return [c for c in self.changes if c["flagged"]]

    def to_json(self) -> dict:
        """The interface of ``history --json`` (docs/history.md)."""
        summary = {}
        for (when, q), r in self.summary.iterrows():
            summary.setdefault(when, {})[q] = {c: float(r[c]) for c in ("mean", "sd", "hdi_low", "hdi_high")}
        return {
            "serial": self.serial, "dates": [_iso(d) for d in self.dates], "files": self.files,
            "summary": summary,
            "changes": [{"quantity": c["quantity"], "date": _iso(c["date"]), "probability": c["probability"],
                         "delta": c["delta"], "threshold": c["threshold"]} for c in self.flagged],
            "forecast": [{"quantity": f["quantity"], "recalibrate_by": f["recalibrate_by"] and _iso(f["recalibrate_by"]),
                          "tolerance": f["tolerance"]} for f in self.forecast],
            "diagnostics": {"acceptance": self.fit.acceptance, "tau_max_steps": self.fit.tau_max,
                            "false_alarm_rate": ALPHA, "flag_level": self.changes[0]["level"] if self.changes else None},
            "output": self.output,
        }

    def to_text(self) -> str:
        lines = [f"History of machine {self.serial or '(no serial)'}: {len(self.dates)} campaigns, "
                 f"{_iso(self.dates[0])} to {_iso(self.dates[-1])} (random-walk drift model, linear model)"]
        last = self.dates[-1]
        lines.append(f"{'quantity':18s} {'ISO':10s} {'unit':>4s} {'first':>16s} {'last':>16s}")
        for q in self.fit.quantities:
            a, b = self.summary.loc[(_iso(self.dates[0]), q)], self.summary.loc[(_iso(last), q)]
            lines.append(f"{q:18s} {iso_symbol(q) or '—':10s} {units.SYMBOL[quantity_unit(q)]:>4s} "
                         f"{a['mean']:8.2f} ± {a['sd']:5.2f} {b['mean']:8.2f} ± {b['sd']:5.2f}")
        level = self.changes[0]["level"] if self.changes else 1.0
        lines += ["", f"Changes flagged (P(|Δ| > threshold) > {level:.4f}: family-wise false-alarm rate ≤ "
                  f"{100 * ALPHA:g} % over {len(self.changes)} quantity × interval pairs):"]
        lines += [f"  {c['quantity']} before {_iso(c['date'])}: Δ = {c['delta']:+.2f} "
                  f"{units.SYMBOL[quantity_unit(c['quantity'])]}, P(|Δ| > {c['threshold']:g}) = {c['probability']:.4f}"
                  for c in self.flagged] or ["  none"]
        if self.forecast:
            lines += ["", f"Forecast: the date by which P(out of tolerance) passes {100 * FORECAST_RISK:g} % "
                      f"(horizon {HORIZON_YEARS:g} years):"]
            lines += [f"  {f['quantity']} (tolerance {f['tolerance']}): "
                      f"{_iso(f['recalibrate_by']) if f['recalibrate_by'] else 'beyond the horizon'}" for f in self.forecast]
        if self.output:
            lines += ["", f"written to {self.output}/: {', '.join(self.written)}"]
        return "\n".join(lines)

    def write(self, out_dir) -> list[str]:
        """history.json, history_summary.csv, changes.csv, forecast.csv, trend.png and index.html into ``out_dir``
        (atomically)."""
        from .figures import trend_figure

        out_dir = Path(out_dir)
        files = ["index.html", "history.json", "history_summary.csv", "changes.csv", "forecast.csv", "trend.png"]
        with atomic_directory(out_dir) as tmp:
            self.output = str(out_dir)
            self.written = files
            (tmp / "history.json").write_text(json_text(self.to_json()) + "\n", encoding="utf-8")
            self.summary.to_csv(tmp / "history_summary.csv", float_format="%.6g")
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
        wide = self.summary.reset_index().pivot(index="date", columns="quantity", values="mean")
        page.table(wide[[q for q in self.fit.quantities if q in wide.columns]], digits=2)
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


def summary_frame(hf: HistoryFit, dates) -> pd.DataFrame:
    """Rows (date, quantity): mean, sd and the 95 % HDI of the mixture posterior (display units; the HDI from 50
    draws per scale draw)."""
    rng = np.random.default_rng(0)
    rows = {}
    for t, when in enumerate(dates):
        for k, q in enumerate(hf.quantities):
            m, s = hf.mean[:, t, k], hf.sd[:, t, k]
            draws = (m[:, None] + s[:, None] * rng.standard_normal((len(m), 50))).ravel()
            lo, hi = az.hdi(draws, hdi_prob=0.95)
            rows[(_iso(when), q)] = {"mean": float(m.mean()), "sd": float(np.sqrt(np.mean(s**2) + np.var(m))),
                                           "hdi_low": float(lo), "hdi_high": float(hi)}
    df = pd.DataFrame.from_dict(rows, orient="index")
    df.index = pd.MultiIndex.from_tuples(df.index, names=["date", "quantity"])
    return df
