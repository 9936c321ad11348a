"""The fleet at a glance: the console table, ``index.html`` (machines × quantities), ``fleet_summary.csv``.

Each cell of the overview is the latest campaign's posterior mean ± sd of a quantity, flagged with its
conformity verdict (the campaign's own ``[tolerances]``), a drift flag when the machine's history found a
change in it, and the date by which the history forecasts it leaves its tolerance (recalibrate by).
"""

from __future__ import annotations

import html
import math

import pandas as pd

from .. import units
from ..html_page import Page
from ..parameters import IDENTIFIABLE
from ..posterior.conformity import CONFORMS, DOES_NOT_CONFORM, UNDECIDED

#: the quantities of the overview: the eight of the thesis ball-bar procedure
OVERVIEW_QUANTITIES = IDENTIFIABLE

#: one-character flags of the console table, and their meaning
FLAGS = {DOES_NOT_CONFORM: "!", UNDECIDED: "?", CONFORMS: ""}
DRIFT_FLAG = "Δ"
_CSS = """<style>
td.cell{white-space:nowrap}.ok{background:#e9f6ef}.bad{background:#fde8e4}.maybe{background:#fff4e5}
.flag{font-size:.8em;display:block;color:#555}.drift{color:#b34000;font-weight:bold}
</style>"""


def _quantities(result) -> list[str]:
    seen = [q for m in result.machines for q in m["latest"]]
    return [q for q in OVERVIEW_QUANTITIES if q in seen]


def _machine_name(m: dict) -> str:
    return m["serial"] if m["serial"] is not None else m["id"].removeprefix("file:")


def _flags(cell: dict) -> str:
    return FLAGS.get(cell.get("conformity") or "", "") + (DRIFT_FLAG if cell.get("drift") else "")


def _recalibrate_by(m: dict) -> str | None:
    dates = sorted(f["recalibrate_by"] for f in m["forecast"] if isinstance(f, dict) and f.get("recalibrate_by"))
    return dates[0] if dates else None


def display(value, unit: str | None, digits: int = 2) -> str:
    """``-24.11″`` / ``3.2 µm``; ``—`` for a missing value."""
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "—"
    return f"{value:.{digits}f}{' ' if unit == 'um' else ''}{units.SYMBOL.get(unit, '') if unit else ''}"


# --------------------------------------------------------------------------- console
def text_overview(result) -> str:
    qs = _quantities(result)
    n_campaigns = sum(len(m["campaigns"]) for m in result.machines)
    s = result.settings
    lines = [f"Fleet below {result.directory}: {len(result.machines)} machines, {n_campaigns} campaigns "
             f"(model {s.model}, seed {s.seed}); latest posterior mean per quantity, "
             f"! does not conform, ? undecided, {DRIFT_FLAG} changed (history)", ""]
    rows = [["machine", "campaigns", "latest"] + qs + ["recalibrate by"]]
    for m in result.machines:
        last = next(iter(m["latest"].values()), {})
        rows.append([_machine_name(m), str(len(m["campaigns"])), last.get("date") or "—"]
                    + [display(m["latest"][q]["mean"], m["latest"][q]["unit"], 1) + _flags(m["latest"][q])
                       if q in m["latest"] else "—" for q in qs] + [_recalibrate_by(m) or "—"])
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines += ["  ".join(v.ljust(w) if i < 3 else v.rjust(w) for i, (v, w) in enumerate(zip(r, widths))).rstrip()
              for r in rows]
    for m in result.machines:
        for c in m["changes"]:
            lines.append(f"  {_machine_name(m)}: change in {c.get('quantity')} at {c.get('date')}"
                         + (f" (probability {c['probability']:.2f})" if isinstance(c.get("probability"), float) else ""))
        lines += [f"  {_machine_name(m)}: {n}" for n in m["notes"]]
    if result.errors:
        lines += ["", f"{len(result.errors)} failed (the rest completed):"] + [f"  {e['message']}" for e in result.errors]
    r = result.run
    where = f"scheduler {r['scheduler']}" if r["scheduler"] else f"a local cluster of {r['workers']} worker{'s' * (r['workers'] != 1)}"
    lines += ["", f"{r['units']} units: {r['cached']} from the cache, {r['computed']} computed"
              + (f" on {where}" if r["computed"] else "") + f", {r['wall_time_s']:.0f} s"]
    if result.files:
        lines.append(f"wrote {result.files[0]} and {len(result.files) - 1} more files")
    return "\n".join(lines)


# --------------------------------------------------------------------------- CSV
def summary_table(result) -> pd.DataFrame:
    """One row per machine × quantity: the latest campaign's mean, sd, 95 % HDI, conformity, drift, recalibrate-by."""
    rows = []
    for m in result.machines:
        for q, c in m["latest"].items():
            rows.append({"serial": m["serial"], "machine": m["id"], "quantity": q, "unit": c["unit"],
                         "date": c["date"], "file": c["file"], "mean": c["mean"], "sd": c["sd"],
                         "hdi_low": c["hdi_low"], "hdi_high": c["hdi_high"], "conformity": c["conformity"],
                         "p_nonconformance": c["p_nonconformance"], "drift": c["drift"], "drift_date": c["drift_date"],
                         "drift_probability": c["drift_probability"], "recalibrate_by": c["recalibrate_by"],
                         "page": m["page"]})
    return pd.DataFrame(rows, columns=["serial", "machine", "quantity", "unit", "date", "file", "mean", "sd", "hdi_low",
                                       "hdi_high", "conformity", "p_nonconformance", "drift", "drift_date",
                                       "drift_probability", "recalibrate_by", "page"])


# --------------------------------------------------------------------------- HTML
def _cell(c: dict | None) -> str:
    if c is None:
        return '<td class="num">—</td>'
    kind = {CONFORMS: "ok", DOES_NOT_CONFORM: "bad", UNDECIDED: "maybe"}.get(c.get("conformity") or "", "")
    parts = [html.escape(f"{display(c['mean'], c['unit'])} ± {display(c['sd'], c['unit'])}")]
    if c.get("conformity"):
        p = c.get("p_nonconformance")
        parts.append(f'<span class="flag">{html.escape(c["conformity"])}'
                     + (f", P(out) {p:.2f}" if isinstance(p, float) else "") + "</span>")
    if c.get("drift"):
        parts.append(f'<span class="flag drift">{DRIFT_FLAG} changed {html.escape(str(c.get("drift_date") or ""))}</span>')
    if c.get("recalibrate_by"):
        parts.append(f'<span class="flag">recalibrate by {html.escape(str(c["recalibrate_by"]))}</span>')
    return f'<td class="num cell {kind}">{"".join(parts)}</td>'


def overview_page(result) -> Page:
    qs = _quantities(result)
    page = Page(f"Fleet overview — {len(result.machines)} machines below {result.directory}")
    page.raw(_CSS)
    page.section("machines", "Machines")
    page.paragraph("Each cell: the latest campaign's posterior mean ± sd; its conformity verdict where the campaign "
                   f"has tolerances (green conforms, red does not, amber undecided); {DRIFT_FLAG} where the machine's "
                   "history found a change; the date by which the history forecasts the quantity to leave its "
                   "tolerance.  Each machine links to its page.")
    head = "".join(f"<th>{html.escape(h)}</th>" for h in ["machine", "campaigns", "latest", *qs, "recalibrate by"])
    body = []
    for m in result.machines:
        last = next(iter(m["latest"].values()), {})
        link = f'<a href="{html.escape(m["page"])}">{html.escape(_machine_name(m))}</a>'
        if m["history"] is not None:
            campaigns = m["page"].rsplit("/", 1)[0] + "/campaigns.html"
            link += f' (<a href="{html.escape(campaigns)}">campaigns</a>)'
        body.append(f"<tr><td>{link}</td><td class=\"num\">{len(m['campaigns'])}</td>"
                    f"<td>{html.escape(str(last.get('date') or '—'))}</td>"
                    + "".join(_cell(m["latest"].get(q)) for q in qs)
                    + f"<td>{html.escape(_recalibrate_by(m) or '—')}</td></tr>")
    page.raw(f"<table><thead><tr>{head}</tr></thead><tbody>{''.join(body)}</tbody></table>")
    notes = [f"{_machine_name(m)}: {n}" for m in result.machines for n in m["notes"]]
    page.box("missing", "Notes", notes)
    if result.errors:
        page.section("errors", f"Failed ({len(result.errors)}; the rest completed)")
        page.box("warn", "Not computed", [e["message"] for e in result.errors])
    s, r = result.settings, result.run
    page.section("run", "How this was computed")
    page.paragraph(f"Model {s.model}, sampler {s.sampler}, seed {s.seed} (each campaign seeded from its content and "
                   f"this seed), target ESS {s.target_ess:g}. {r['units']} units: {r['cached']} from the cache, "
                   f"{r['computed']} computed, {r['failed']} failed.")
    return page


def machine_page(result, m: dict) -> Page:
    """A machine's campaigns side by side: each quantity's posterior mean ± sd (and verdict) per campaign."""
    page = Page(f"Machine {_machine_name(m)} — {len(m['campaigns'])} campaign(s)")
    page.raw(f'<p>Part of the fleet below {html.escape(str(result.directory))} '
             '(<a href="../../index.html">overview</a>).</p>')
    page.section("campaigns", "Campaigns")
    page.table(pd.DataFrame([{"file": c["file"], "date": c["date"] or "—", "temperature °C": c["temperature_C"],
                              "converged": c["diagnostics"]["converged"], "warnings": len(c["warnings"])}
                             for c in m["campaigns"]]), index=False, digits=1)
    if m["campaigns"]:
        page.section("quantities", "Posterior per campaign (mean ± sd)")
        cols = {}
        for c in m["campaigns"]:
            label = c["date"] or c["file"]
            cols[label] = {q: f"{display(s['mean'], s['unit'])} ± {display(s['sd'], s['unit'])}"
                           + (f" ({s['conformity']})" if s.get("conformity") else "")
                           for q, s in c["summary"].items()}
        page.table(pd.DataFrame(cols), index=True)
    page.box("missing", "Notes", m["notes"])
    page.box("warn", "Sampler warnings", [f"{c['file']}: {w}" for c in m["campaigns"] for w in c["warnings"]])
    return page
