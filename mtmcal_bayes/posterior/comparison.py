"""The posterior beside every deterministic value the machine has: is each inside the 95 % HDI, how many sd away.

One comparison on every machine.  Its references are what the machine provides: the least-squares identification
(every machine, :mod:`.least_squares`) and the values of its plug-in's own method, where it has one (the thesis':
the ball-bar values of Eqs 4.10–4.18 and the touch-probe values as printed and recomputed; its result's
``references()``).
"""

from __future__ import annotations

import pandas as pd

#: the kinds of deterministic value a posterior may be compared with, as columns of :func:`comparison`, in the order
#: the figures draw them: the thesis plug-in's three, then the least squares of every machine
REFERENCES = ("ballbar", "probe_reported", "probe_recomputed", "least_squares")


def references(own=None, least_squares=None) -> dict[str, dict[str, float | None]]:
    """The deterministic values to set beside a posterior, by kind (:data:`REFERENCES`) then quantity (display
    units; ``None`` where a method addresses a quantity but gives it no value): those of ``own``, the result of the
    machine's plug-in's identification (anything with ``references()``), and those of ``least_squares`` (a
    :class:`~.least_squares.LeastSquares`), each where given."""
    out = dict(own.references()) if own is not None else {}
    if least_squares is not None:
        out["least_squares"] = least_squares.values()
    return out


def comparison(summary: pd.DataFrame, refs: dict[str, dict[str, float | None]]) -> pd.DataFrame:
    """Each quantity's posterior against the deterministic values ``refs`` (:func:`references`).

    Rows: the quantities of ``summary`` (in its order) that some reference addresses.  Columns: ``unit, mean, sd,
    hdi_low, hdi_high`` from the summary, then per reference kind (in the order of ``refs``) its value ``KIND``,
    whether it lies in the 95 % HDI ``KIND_in_hdi`` and its distance from the posterior mean in posterior sd
    ``KIND_z`` (``None`` where the kind gives the quantity no value).  No reference: an empty table.
    """
    rows = []
    for name in [n for n in summary.index if any(n in values for values in refs.values())]:
        r = summary.loc[name]
        row = {"quantity": name, "unit": r["unit"], "mean": r["mean"], "sd": r["sd"],
               "hdi_low": r["hdi_low"], "hdi_high": r["hdi_high"]}
        for key, values in refs.items():
            v = values.get(name)
            row[key] = v
            row[f"{key}_in_hdi"] = None if v is None else bool(r["hdi_low"] <= v <= r["hdi_high"])
            row[f"{key}_z"] = None if v is None else (v - r["mean"]) / r["sd"]
        rows.append(row)
    return pd.DataFrame(rows).set_index("quantity") if rows else pd.DataFrame()
