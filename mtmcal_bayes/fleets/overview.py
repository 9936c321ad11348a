"""The fleet at a glance: the console table, ``index.html`` (machines × quantities), ``fleet_summary.csv``.

Each cell of the overview is a machine's latest estimate of a quantity (``FleetResult.machines[i]["latest"]``):
the history's at its latest date where the machine has a history (all its campaigns jointly), else its latest
campaign's posterior; mean ± sd, the conformity verdict decided on that estimate (the plant-wide tolerances or
the campaign's own ``[tolerances]``), a drift flag when the history found a change in it, and the date by which
the history forecasts it leaves its tolerance (recalibrate by).  The value links to the latest campaign's own
posterior on the machine's page.  The page's column is 1180 px wide: a cell is one short line of value and a
line of small badges, the heads are the quantities' symbols, their names and units in a legend.
"""

from __future__ import annotations

import html
import math

import pandas as pd

from .. import units
from ..campaign import tolerance_text
from ..html_page import Page
from ..iso import iso_symbol
from ..parameters import IDENTIFIABLE, QUANTITIES, quantity_unit
from ..posterior.conformity import CONFORMS, DOES_NOT_CONFORM, UNDECIDED

#: the quantities of the overview: the eight of the thesis ball-bar procedure
OVERVIEW_QUANTITIES = IDENTIFIABLE

#: one-character flags of the console table, and their meaning
FLAGS = {DOES_NOT_CONFORM: "!", UNDECIDED: "?", CONFORMS: ""}
DRIFT_FLAG = "Δ"
#: the overview's marks: conformity, a change the history found, the forecast's recalibrate-by date
MARKS = {CONFORMS: "✓", DOES_NOT_CONFORM: "✗", UNDECIDED: "?"}
RECALIBRATE_MARK = "↻"
_CSS = """<style>
table.fleet th,table.fleet td{padding:3px 5px;vertical-align:top}table.fleet th.q{text-align:center}
td.q{text-align:right;font-variant-numeric:tabular-nums}td.q a.v{white-space:nowrap;color:inherit;
text-decoration:none;border-bottom:1px dotted #777}.ok{background:#e9f6ef}.bad{background:#fde8e4}
.maybe{background:#fff4e5}.b{display:inline-block;white-space:nowrap;font-size:.78em;color:#444;margin-left:3px}
.b.drift{color:#b34000;font-weight:bold}.sub{font-size:.8em;color:#555;white-space:nowrap}
p.legend{font-size:.86em;color:#333}
</style>"""
_GREEK = {"alpha": "α", "beta": "β", "gamma": "γ", "sigma": "σ", "dx": "δx", "dy": "δy", "dz": "δz"}


def html_symbol(name: str) -> str:
    """The quantity's symbol as HTML: ``beta_XB`` → β<sub>XB</sub>, ``dx_CZ_minus_dx_BT`` →
    δx<sub>CZ</sub>−δx<sub>BT</sub>."""
    def one(n: str) -> str:
        head, _, sub = n.partition("_")
        return f"{_GREEK.get(head, html.escape(head))}<sub>{html.escape(sub)}</sub>" if sub else html.escape(n)

    return "−".join(one(part) for part in name.split("_minus_"))


def campaigns_page(m: dict) -> str:
    """The machine's page of campaigns, below the overview: ``campaigns.html`` beside its history page, else its
    ``index.html``."""
    return m["page"].rsplit("/", 1)[0] + "/campaigns.html" if m["history"] is not None else m["page"]


def campaign_anchor(index: int) -> str:
    """The id of the ``index``-th (0-based) campaign's section on its machine's page of campaigns."""
    return f"campaign-{index + 1}"


def _decimals(sd) -> int:
    """Decimals that show the sd with two significant digits (0 to 3)."""
    if not isinstance(sd, (int, float)) or not math.isfinite(sd) or sd <= 0:
        return 2
    return min(3, max(0, 1 - math.floor(math.log10(sd))))


def estimate_text(c: dict) -> str:
    """``9.7 ± 1.6″`` / ``-3.41 ± 0.32 µm``: the mean ± sd of a ``latest`` entry, the sd to two digits."""
    if c.get("mean") is None:
        return "—"
    d = _decimals(c.get("sd"))
    sd = "?" if c.get("sd") is None else f"{c['sd']:.{d}f}"
    unit = c.get("unit")
    return f"{c['mean']:.{d}f} ± {sd}{' ' if unit == 'um' else ''}{units.SYMBOL.get(unit, '') if unit else ''}"


def _quantities(result) -> list[str]:
    """The overview's columns: the thesis' eight that any machine has, then every described machine's own
    deviations (ISO 230-7 names) in the order the machines bring them; each machine fills its own."""
    seen = [q for m in result.machines for q in m["latest"]]
    own = [q for m in result.machines for q in _own(m) if q in seen and q not in OVERVIEW_QUANTITIES]
    return [q for q in OVERVIEW_QUANTITIES if q in seen] + list(dict.fromkeys(own))


def _own(m: dict) -> list[str]:
    """The quantities a machine has: a described machine's deviations, else the thesis' eight."""
    return list(m["deviations"]) if m.get("deviations") is not None else list(OVERVIEW_QUANTITIES)


def _has(m: dict, q: str) -> bool:
    return q in _own(m)


#: what a cell of a deviation the machine has but its campaigns do not determine shows (never a number)
NOT_DETERMINED = "n.d."


def _why_not(m: dict, q: str) -> str | None:
    """Why a described machine's quantity is not shown as measured (None: it is, or it is not the machine's)."""
    return next((x["why"] for x in m.get("not_determined", []) if x["quantity"] == q), None)


def _html_cell(m: dict, q: str) -> str:
    """A machine × quantity cell: blank for a quantity it does not have, n.d. for one not determined, else its
    estimate."""
    if not _has(m, q):
        return '<td class="q"></td>'
    why = _why_not(m, q)
    if why is not None and q not in m["latest"]:
        return f'<td class="q sub" title="{html.escape("not determined: " + why)}">{NOT_DETERMINED}</td>'
    return _cell(m["latest"].get(q))


def _text_cell(m: dict, q: str) -> str:
    if q in m["latest"]:
        return display(m["latest"][q]["mean"], m["latest"][q]["unit"], 1) + _flags(m["latest"][q])
    if not _has(m, q):
        return ""
    return NOT_DETERMINED if _why_not(m, q) is not None else "—"


def _meaning(result, q: str) -> str:
    if q in QUANTITIES:
        return QUANTITIES[q].meaning
    return next((m["deviations"][q] for m in result.machines if q in (m.get("deviations") or {})), q)


def _kind(m: dict) -> str:
    """``type, description`` of a machine in words (``"TYPE-A, trunnion"``, ``"thesis machine"``)."""
    return ", ".join(x for x in (m.get("type"), m.get("description")) if x)


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


def _source(m: dict) -> str:
    """What a machine's overview shows: ``history`` where its latest estimates are the history's, else ``campaign``."""
    return "history" if any(c.get("source") == "history" for c in m["latest"].values()) else "campaign"


def _tolerances_text(result) -> str:
    tol = result.settings.to_json().get("tolerances")
    if tol is None:
        return "each machine's latest campaign's own [tolerances]"
    return "the plant-wide set given to the fleet: " + ", ".join(
        f"{n} {tolerance_text(t['low'], t['high'], quantity_unit(n))}" for n, t in tol.items())


#: how conformity is decided on what the overview shows (said on the page and in the docs)
CONFORMITY_RULE = ("Conformity is decided on the estimate shown. For a history estimate, taken as normal with its "
                   "mean and sd: P(outside) = Φ((low − mean)/sd) + Φ((mean − high)/sd); it conforms when mean ± "
                   "1.96 sd lies inside the tolerance, does not conform when that interval lies wholly outside, and "
                   "is undecided when it straddles a limit (ISO 14253-1 with guard bands of the uncertainty). For a "
                   "single campaign's posterior, the campaign's own verdict: its 95 % HDI against the tolerance, "
                   "P(outside) the share of its draws outside.")


# --------------------------------------------------------------------------- console
def text_overview(result) -> str:
    qs = _quantities(result)
    n_campaigns = sum(len(m["campaigns"]) for m in result.machines)
    s = result.settings
    lines = [f"Fleet below {result.directory}: {len(result.machines)} machines, {n_campaigns} campaigns "
             f"(model {s.model}, seed {s.seed}); latest mean per quantity: the history's at the latest date "
             f"(else the latest campaign's), ! does not conform, ? undecided, {DRIFT_FLAG} changed (history)", ""]
    rows = [["machine", "campaigns", "latest", "from"] + qs + ["recalibrate by"]]
    for m in result.machines:
        last = next(iter(m["latest"].values()), {})
        rows.append([_machine_name(m), str(len(m["campaigns"])), last.get("date") or "—", _source(m)]
                    + [_text_cell(m, q) for q in qs] + [_recalibrate_by(m) or "—"])
    widths = [max(len(r[i]) for r in rows) for i in range(len(rows[0]))]
    lines += ["  ".join(v.ljust(w) if i < 4 else v.rjust(w) for i, (v, w) in enumerate(zip(r, widths))).rstrip()
              for r in rows]
    if s.tolerances is not None:
        lines.append(f"  tolerances: {_tolerances_text(result)}")
    for m in result.machines:
        for c in m["changes"]:
            lines.append(f"  {_machine_name(m)}: change in {c.get('quantity')} at {c.get('date')}"
                         + (f" (probability {c['probability']:.2f})" if isinstance(c.get("probability"), float) else ""))
        lines += [f"  {_machine_name(m)}: {n}" for n in m["notes"]]
        if m.get("deviations") is not None:
            lines.append(f"  {_machine_name(m)}: {_kind(m)}; not determined ({NOT_DETERMINED}), not shown as measured: "
                         + (", ".join(x["quantity"] for x in m.get("not_determined", [])) or "none"))
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
SUMMARY_COLUMNS = ["serial", "machine", "quantity", "unit", "date", "file", "mean", "sd", "hdi_low", "hdi_high",
                   "conformity", "p_nonconformance", "drift", "drift_date", "drift_probability", "recalibrate_by",
                   "page", "source", "campaign_mean", "campaign_sd", "campaign_conformity",
                   "campaign_p_nonconformance", "type", "configuration", "description"]


def summary_table(result) -> pd.DataFrame:
    """One row per machine × quantity: the latest estimate (``source``: the history's at the latest date, or the
    latest campaign's posterior) with its mean, sd, 95 % HDI, conformity, drift, recalibrate-by, and the single
    latest campaign's own mean, sd and verdict beside it."""
    rows = []
    for m in result.machines:
        for q, c in m["latest"].items():
            own = c.get("campaign") or {}
            rows.append({"serial": m["serial"], "machine": m["id"], "quantity": q, "unit": c["unit"],
                         "date": c["date"], "file": c["file"], "mean": c["mean"], "sd": c["sd"],
                         "hdi_low": c["hdi_low"], "hdi_high": c["hdi_high"], "conformity": c["conformity"],
                         "p_nonconformance": c["p_nonconformance"], "drift": c["drift"], "drift_date": c["drift_date"],
                         "drift_probability": c["drift_probability"], "recalibrate_by": c["recalibrate_by"],
                         "page": m["page"], "source": c.get("source"), "campaign_mean": own.get("mean"),
                         "campaign_sd": own.get("sd"), "campaign_conformity": own.get("conformity"),
                         "campaign_p_nonconformance": own.get("p_nonconformance"), "type": m.get("type"),
                         "configuration": m.get("configuration"), "description": m.get("description")})
    return pd.DataFrame(rows, columns=SUMMARY_COLUMNS)


# --------------------------------------------------------------------------- HTML
def _cell_title(c: dict) -> str:
    """The hover text of a cell: where the estimate comes from, the single campaign's own, the flags in words."""
    own = c.get("campaign")
    parts = [(f"history estimate at {c['date']}, all campaigns jointly" if c.get("source") == "history"
              else f"latest campaign's posterior ({c.get('date') or c.get('file')})") + f": {estimate_text(c)}"]
    if own is not None and c.get("source") == "history":
        parts.append(f"latest campaign alone ({own.get('date')}): {estimate_text({**own, 'unit': c.get('unit')})}"
                     + (f", {own['conformity']}" if own.get("conformity") else "") + " (click)")
    if c.get("conformity"):
        t = c.get("tolerance") or {}
        parts.append(f"{c['conformity']} to {tolerance_text(t.get('low'), t.get('high'), c['unit'])}"
                     + (f", P(outside) {c['p_nonconformance']:.4f}"
                        if isinstance(c.get("p_nonconformance"), float) else ""))
    if c.get("drift"):
        p = c.get("drift_probability")
        parts.append(f"changed at {c.get('drift_date')}" + (f" (P {p:.2f})" if isinstance(p, float) else ""))
    if c.get("recalibrate_by"):
        parts.append(f"recalibrate by {c['recalibrate_by']}")
    return "; ".join(parts)


def _cell(c: dict | None) -> str:
    if c is None:
        return '<td class="q">—</td>'
    kind = {CONFORMS: "ok", DOES_NOT_CONFORM: "bad", UNDECIDED: "maybe"}.get(c.get("conformity") or "", "")
    value = html.escape(estimate_text(c))
    own = c.get("campaign")
    value = f'<a class="v" href="{html.escape(own["page"])}">{value}</a>' if own and own.get("page") else value
    badges = []
    if c.get("conformity"):
        p = c.get("p_nonconformance")
        badges.append(f'<span class="b">{MARKS.get(c["conformity"], "")}'
                      + (f" {p:.2f}" if isinstance(p, float) else "") + "</span>")
    if c.get("drift"):
        badges.append(f'<span class="b drift">{DRIFT_FLAG} {html.escape(str(c.get("drift_date") or ""))}</span>')
    if c.get("recalibrate_by"):
        badges.append(f'<span class="b">{RECALIBRATE_MARK} {html.escape(str(c["recalibrate_by"]))}</span>')
    second = f"<br>{''.join(badges)}" if badges else ""
    classes = f"q {kind}" if kind else "q"
    return f'<td class="{classes}" title="{html.escape(_cell_title(c))}">{value}{second}</td>'


def _head(q: str, meaning: str) -> str:
    iso = iso_symbol(q)
    title = f"{q}{f' ({iso})' if iso else ''}, {units.SYMBOL[quantity_unit(q)]}: {meaning}"
    return f'<th class="q" title="{html.escape(title)}">{html_symbol(q)}</th>'


def _machine_cell(m: dict) -> str:
    n = len(m["campaigns"])
    last = next(iter(m["latest"].values()), {})
    own = campaigns_page(m)
    return (f'<td><a href="{html.escape(m["page"])}">{html.escape(_machine_name(m))}</a><br>'
            f'<span class="sub"><a href="{html.escape(own)}">{n} campaign{"s" * (n != 1)}</a></span><br>'
            f'<span class="sub">{_source(m)}, {html.escape(str(last.get("date") or "—"))}</span>'
            + (f'<br><span class="sub">{html.escape(_kind(m))}</span>' if _kind(m) else "") + "</td>")


def overview_page(result) -> Page:
    qs = _quantities(result)
    page = Page(f"Fleet overview — {len(result.machines)} machines below {result.directory}")
    page.raw(_CSS)
    page.section("machines", "Machines")
    page.paragraph("Each cell: the machine's latest estimate, mean ± sd — the history's at its latest date (all "
                   "its campaigns jointly, docs/history.md) where the machine has a history, else its latest "
                   "campaign's posterior (the machine's column says which). The value links to the latest "
                   "campaign's own posterior on the machine's page, and hovering it shows that campaign's value. "
                   f"Below: {MARKS[CONFORMS]} conforms, {MARKS[DOES_NOT_CONFORM]} does not conform, "
                   f"{MARKS[UNDECIDED]} undecided, with P(outside the tolerance) (green, red, amber); {DRIFT_FLAG} "
                   f"date: the history found a change there; {RECALIBRATE_MARK} date: recalibrate by (the history's "
                   "forecast of when the quantity leaves its tolerance).")
    head = "".join(["<th>machine</th>", *(_head(q, _meaning(result, q)) for q in qs), "<th>recalibrate by</th>"])
    body = [f"<tr>{_machine_cell(m)}" + "".join(_html_cell(m, q) for q in qs)
            + f"<td>{html.escape(_recalibrate_by(m) or '—')}</td></tr>" for m in result.machines]
    page.raw(f'<table class="fleet"><thead><tr>{head}</tr></thead><tbody>{"".join(body)}</tbody></table>')
    legend = " · ".join(f"{html_symbol(q)} {html.escape(q)}"
                        + (f" ({html.escape(iso_symbol(q))})" if iso_symbol(q) else "")
                        + f", {units.SYMBOL[quantity_unit(q)]}" for q in qs)
    page.raw(f'<p class="legend">{legend}</p>')
    page.paragraph(CONFORMITY_RULE + f" Tolerances: {_tolerances_text(result)}.")
    if any(m.get("deviations") is not None for m in result.machines):
        page.paragraph("Machines of several types and configurations: each machine fills the columns of its own "
                       f"deviations (a blank cell: a quantity the machine does not have; {NOT_DETERMINED}: one of its "
                       "deviations its campaigns do not determine one by one, never shown as measured, the reason on "
                       "hovering and below; — : one it has without a value; docs/fleet.md):")
        page.table(pd.DataFrame([{"machine": _machine_name(m), "type": m.get("type") or "—",
                                  "configuration": m.get("configuration"), "description": m.get("description"),
                                  "not shown as measured": "; ".join(f"{x['quantity']} ({x['why']})"
                                                                     for x in m.get("not_determined", [])) or "—"}
                                 for m in result.machines]), index=False)
    notes = [f"{_machine_name(m)}: {n}" for m in result.machines for n in m["notes"]]
    page.box("missing", "Notes", notes)
    if result.types:
        page.section("sigma-model", "σ_model learnt by machine type")
        page.paragraph("The model-discrepancy scale the histories of each type's machines taught, pooled (machines of "
                       "one type share a hyper-distribution; docs/fleet.md). A new machine of the type samples its "
                       "first campaign with it: mtmcal-bayes sample NEW.toml --sigma-model-prior FILE. Only right when "
                       "the new machine really belongs with the others.")
        page.table(pd.DataFrame([{"type": t["type"], "machines": t["machines"], "histories": t["histories"],
                                  "median µm": t["median_um"], "sd of ln σ": t["log_sd"],
                                  "τ between machines": t["tau"]["mean"],
                                  "prior file": t["prior_file"] or "— (nothing learnt to pass on)"}
                                 for t in result.types.values()]), digits=2, index=False)
    if result.errors:
        page.section("errors", f"Failed ({len(result.errors)}; the rest completed)")
        page.box("warn", "Not computed", [e["message"] for e in result.errors])
    s, r = result.settings, result.run
    page.section("run", "How this was computed")
    page.paragraph(f"Model {s.model}, sampler {s.sampler}, seed {s.seed} (each campaign seeded from its content and "
                   f"this seed), target ESS {s.target_ess:g}. {r['units']} units: {r['cached']} from the cache, "
                   f"{r['computed']} computed, {r['failed']} failed.")
    return page


def _campaign_rows(c: dict, history_at: dict, *, with_history: bool, described: bool = False) -> pd.DataFrame:
    """A campaign's section: each quantity of its posterior; on a described machine with whether the campaign
    determines it (``determined``: no, and how, where its posterior rests on priors)."""
    rows = []
    for q, s in c["summary"].items():
        t = s.get("tolerance") or {}
        h = history_at.get(q)
        d = _decimals(s.get("sd"))
        rows.append({"quantity": q, "mean ± sd": estimate_text(s),
                     "95 % HDI": f"[{display(s.get('hdi_low'), None, d)}, {display(s.get('hdi_high'), None, d)}]",
                     "tolerance": tolerance_text(t.get("low"), t.get("high"), s["unit"]) if t else None,
                     "P(outside)": s.get("p_nonconformance"), "verdict": s.get("conformity"),
                     **({"history at this date": estimate_text({**h, "unit": s["unit"]}) if h else None}
                        if with_history else {}),
                     **({"determined": "yes" if s.get("identified") is not False
                         else f"no ({s.get('identification')})"} if described else {})})
    return pd.DataFrame(rows)


def machine_page(result, m: dict) -> Page:
    """A machine's campaigns side by side (each quantity's posterior mean ± sd and verdict per campaign), then each
    campaign's own section (``#campaign-<k>``, what the overview links to) with the history's estimate at its date."""
    page = Page(f"Machine {_machine_name(m)} — {len(m['campaigns'])} campaign(s)")
    page.raw(f'<p>Part of the fleet below {html.escape(str(result.directory))} '
             '(<a href="../../index.html">overview</a>).</p>')
    if _kind(m):
        page.paragraph(f"Machine: {_kind(m)}, configuration {m.get('configuration') or '—'}.")
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
        page.section("each", "Each campaign")
        summary = (m["history"] or {}).get("summary") or {}
        links = " · ".join(f'<a href="#{campaign_anchor(i)}">{html.escape(c["date"] or c["file"])}</a>'
                           for i, c in enumerate(m["campaigns"]))
        page.raw(f"<p>{links}</p>")
        if summary:
            page.paragraph("Each campaign's own posterior, and the history's estimate at its date (all the machine's "
                           "campaigns jointly: what the overview shows for the latest date).")
        for i, c in enumerate(m["campaigns"]):
            page.raw(f'<h3 id="{campaign_anchor(i)}">{html.escape(c["date"] or "undated")} — '
                     f'{html.escape(c["file"])}</h3>')
            page.table(_campaign_rows(c, summary.get(c["date"]) or {}, with_history=bool(summary),
                                      described=m.get("deviations") is not None), index=False, digits=4)
    page.box("missing", "Notes", m["notes"])
    page.box("warn", "Sampler warnings", [f"{c['file']}: {w}" for c in m["campaigns"] for w in c["warnings"]])
    return page
