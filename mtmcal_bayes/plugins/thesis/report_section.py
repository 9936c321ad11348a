"""The report's section that only makes sense for the thesis machine: the thesis' values recomputed beside the
printed ones (its ``report_section`` contribution; the report writes the same tables as CSV files)."""

from __future__ import annotations


def report_section(page, ident, effect, sigma_um: float) -> None:
    """Add to ``page`` (a :class:`~mtmcal_bayes.reporting.html.Page`) the thesis' deterministic identification
    ``ident`` beside its printed values, and ``effect`` (a DataFrame, or ``None``), that of its assumption dx_BT = 0
    at σ_model = ``sigma_um`` µm."""
    page.section("thesis", "Thesis values recomputed")
    page.paragraph("The deterministic identification of the thesis, recomputed from this campaign beside the values "
                   "printed in the thesis, with its flags (identification_ballbar.csv, identification_probe.csv).")
    page.raw("<h3>Ball bar (Table 4.5, Eqs 4.10–4.18)</h3>")
    page.table(ident.table("ballbar"), index=False)
    page.raw("<h3>Touch probe (Table 5.3, Eqs 5.1–5.19)</h3>")
    if ident.probe:
        page.table(ident.table("probe"), index=False)
    else:
        page.paragraph("No touch-probe data in this campaign.")
    page.box("missing", "Checks the deterministic method leaves out", ident.checks)
    page.box("missing", "Assumptions", ident.assumptions)
    if effect is not None:
        page.paragraph("The thesis assumes dx_BT = 0 (Eq 4.2). Its effect on beta_XB and dx_CZ − dx_BT, closed form "
                       f"at σ_model = {sigma_um:.2f} µm (thesis_assumption_dx_BT.csv):")
        page.table(effect)
