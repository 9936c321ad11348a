"""The report's sections about a machine's description and what its campaign determines (SPEC §19, §20): the chain
and its location errors drawn, the Jacobian's identifiability with each combination's posterior, the least-squares
identification beside the posterior (every machine's deterministic values, beside those of its plug-in's own method
where it has one) and, for a simulated campaign, its stated truth beside both.  Each section appears where the
campaign and its posterior have what it needs: an identifiability, least-squares values, a stated truth; every
machine has a description (the thesis campaign's is the built-in ``integrex-i200``)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from .. import units
from ..html_page import Page
from ..posterior.least_squares import LeastSquares, least_squares

CHAIN_CAPTION = ("The machine at its home pose: the frame, each rotary axis' nominal line through its point, the "
                 "spindle and a tool of the campaign's length (the key says whose), the linear axes (primed: they "
                 "move the workpiece); the chain from workpiece to tool below.")
DEVIATIONS_CAPTION = ("What each location error means (positive values, exaggerated), as the chain applies it: a "
                      "small rigid displacement of the body the axis carries, turning about the axis' point.")


def shown_together(rep) -> list[str]:
    """The deviations the campaign determines, one by one or in a combination (every deviation when none is)."""
    deviations = [p.name for p in rep.log_posterior.space.parameters if p.group == "deviation"]
    ident = rep.identifiability
    determined = set(ident.determined) | {n for c in ident.combinations for n in c.weights}
    return [n for n in deviations if n in determined] or deviations


def least_squares_of(rep) -> LeastSquares:
    """The least-squares identification of ``rep``'s campaign and data at its posterior median σ_model."""
    return least_squares(rep.log_posterior, rep.identifiability, units.to_internal(rep.sigma_model_um, "um"))


def tables(rep, ls: LeastSquares | None, truth) -> dict[str, pd.DataFrame]:
    """identifiability.csv, combinations.csv and, where given, least_squares.csv and truth.csv (none written with
    its index)."""
    ident = rep.identifiability
    rows = [{"kind": "determined", "quantity": n, "weights": f"{n}: 1"} for n in ident.determined]
    rows += [{"kind": "combination", "quantity": c["name"],
              "weights": "; ".join(f"{k}: {v:.6g}" for k, v in c["weights"].items())} for c in rep.combinations]
    rows += [{"kind": "undetermined", "quantity": n, "weights": f"{n}: 1"} for n in ident.undetermined]
    out = {"identifiability.csv": pd.DataFrame(rows, columns=["kind", "quantity", "weights"]),
           "combinations.csv": pd.DataFrame(rep.combinations).drop(columns="weights", errors="ignore")}
    if ls is not None:
        out["least_squares.csv"] = ls.table
    if truth is not None:
        out["truth.csv"] = truth_table(rep, ls, truth)
    return out


def truth_table(rep, ls: LeastSquares | None, truth) -> pd.DataFrame:
    """The stated truth of a simulated campaign beside the posterior (and the least squares, where given), for every
    quantity the campaign determines (deviations one by one and combinations): ``z`` = (mean − truth) / sd,
    ``in_hdi``."""
    s = rep.summary
    value = {n: units.from_internal(v, s.loc[n, "unit"]) for n, v in truth.deviations.items() if n in s.index}
    items = [(n, {n: 1.0}, s.loc[n, "mean"], s.loc[n, "sd"], s.loc[n, "hdi_low"], s.loc[n, "hdi_high"])
             for n in rep.identifiability.determined]
    items += [(c["name"], c["weights"], c["mean"], c["sd"], c["hdi_low"], c["hdi_high"]) for c in rep.combinations]
    lsq = ls.table.set_index("quantity") if ls is not None else None
    rows = []
    for name, w, mean, sd, low, high in items:
        t = sum(v * value.get(k, 0.0) for k, v in w.items())
        row = {"quantity": name, "truth": t, "mean": mean, "sd": sd, "hdi_low": low, "hdi_high": high,
               "in_hdi": bool(low <= t <= high), "z": (mean - t) / sd}
        if lsq is not None:
            row.update(least_squares=lsq.loc[name, "estimate"], least_squares_u=lsq.loc[name, "u"])
        rows.append(row)
    return pd.DataFrame(rows)


def machine_section(page: Page, description, rep, tmp: Path) -> None:
    """The machine: its description, chain and location errors (figures drawn by
    :func:`~.machine_figure.figure_jobs`)."""
    post = rep.log_posterior
    kind = f"built-in type {description.builtin}" if description.builtin else "described in the campaign"
    page.section("machine", "The machine")
    page.paragraph(f"{description.name or 'The machine'}: configuration {description.configuration} ({kind}; "
                   f"docs/machines.md), squareness in the {description.squareness} form. Deviations estimated (ISO "
                   f"230-7): {', '.join(_named(n, rep.summary) for n in post.space.names if n in rep.summary.index)}.")
    page.figure(tmp / "machine.png", CHAIN_CAPTION, "the machine's chain at the home pose")
    page.figure(tmp / "deviations.png", DEVIATIONS_CAPTION, "what each location error means")


def _named(name: str, summary: pd.DataFrame) -> str:
    """``name``, with its ISO 230-7 symbol where the machine names it otherwise (the thesis' aliases)."""
    iso = summary.loc[name, "iso"] if "iso" in summary.columns else None
    return f"{name} ({iso})" if isinstance(iso, str) and iso and iso != name else name


def determined_section(page: Page, rep) -> None:
    """What the campaign determines, one by one, in combination, not at all (the Jacobian's answer)."""
    ident = rep.identifiability
    page.section("determined", "What this campaign determines")
    page.paragraph("Computed from the campaign's Jacobian at the home pose (deviations and nuisance terms; the T ball "
                   "taken as centred, as the thesis does): a deviation is determined when no direction the data "
                   "cannot see moves it, only in combination when such a direction moves it together with others "
                   "(the combination named is what the data see), not at all when it moves alone — its posterior is "
                   "then its prior. identifiability.csv, combinations.csv.")
    page.box("statement", "Determined", [
        "one by one: " + (", ".join(ident.determined) or "none"),
        *[f"in combination: {c['name']} = {c['mean']:.2f} ± {c['sd']:.2f} {units.SYMBOL[c['unit']]} (95 % HDI "
          f"{c['hdi_low']:.2f} to {c['hdi_high']:.2f})" for c in rep.combinations],
        "not at all: " + (", ".join(ident.undetermined) or "none")])


def least_squares_section(page: Page, rep, ls: LeastSquares) -> None:
    """The least-squares identification beside the posterior, for what the campaign determines."""
    s = rep.summary
    page.section("least-squares", "Least-squares identification beside the posterior")
    page.paragraph(f"The deterministic counterpart on every machine: the least-squares solution of the first order "
                   f"of the machine's kinematic model, the nuisance terms held to their set-up knowledge, the "
                   f"deviations free, at σ_model = {ls.sigma_model_um:.2f} µm (the posterior median); only what the "
                   "campaign determines (one by one, in combination, and the derived quantities whose terms it "
                   "determines). least_squares.csv.")
    lsq = ls.table.set_index("quantity")
    post_mean = {**{c["name"]: (c["mean"], c["sd"]) for c in rep.combinations},
                 **{n: (s.loc[n, "mean"], s.loc[n, "sd"]) for n in lsq.index if n in s.index}}
    page.table(pd.DataFrame({"unit": lsq["unit"].map(units.SYMBOL), "least squares": lsq["estimate"],
                             "u": lsq["u"], "posterior mean": [post_mean[n][0] for n in lsq.index],
                             "posterior sd": [post_mean[n][1] for n in lsq.index]}))


def truth_section(page: Page, truth: pd.DataFrame) -> None:
    page.section("truth", "The stated truth of this simulated campaign")
    n_in = int(truth["in_hdi"].sum())
    page.paragraph(f"{n_in} of {len(truth)} determined quantities have their true value inside the 95 % HDI; z is "
                   "(posterior mean − truth) / posterior sd. truth.csv.")
    page.table(truth.set_index("quantity"), digits=2)
