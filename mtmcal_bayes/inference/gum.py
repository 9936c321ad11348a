"""GUM statement of a posterior quantity: value, standard uncertainty, coverage intervals, and how far to trust them.

The posterior draws are the Monte-Carlo sample of GUM Supplement 1 (JCGM 101): the best estimate is their
mean, the standard uncertainty ``u`` their sd, and the 95 % coverage interval is given both ways GUM-S1
defines it, the shortest (ArviZ's HDI) and the probabilistically symmetric (2.5 % and 97.5 % quantiles).

Where the posterior is close to Gaussian, the expanded uncertainty ``U = k·u`` with ``k = 1.96`` (95 %) is
stated too, validated the GUM-S1 §8 way: the interval ``y ± U`` may differ from the symmetric Monte-Carlo
interval by no more than the numerical tolerance.  GUM-S1's tolerance δ is half a unit in the last digit
of ``u`` stated to two significant digits; a finite run cannot resolve endpoints better than its own
Monte-Carlo error, so the tolerance used is the larger of δ and twice the endpoints' Monte-Carlo standard
error (``az.mcse`` of the quantile, which accounts for autocorrelation).  The same error says how many
significant digits of ``u`` the run supports (GUM-S1 §7.9's adaptive procedure stops when it is below δ).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
from scipy.stats import norm

from .. import units
from ..arviz_import import az
from ..parameters import quantity_unit
from .reading_choice import alternative_clause

#: coverage probability of the stated intervals
COVERAGE = 0.95
#: coverage factor of a Gaussian for :data:`COVERAGE`
K_GAUSSIAN = float(norm.ppf(0.5 + COVERAGE / 2))
#: significant digits of u a statement aims at (GUM 7.2.6: at most two)
DIGITS = 2

GUM_COLUMNS = ["u", "ci95_shortest_low", "ci95_shortest_high", "ci95_symmetric_low", "ci95_symmetric_high",
               "coverage_probability", "U", "k", "U_note", "n_draws", "endpoint_tolerance", "significant_digits"]


def numerical_tolerance(u: float, digits: int = DIGITS) -> float:
    """GUM-S1 §7.9.2: δ = ½·10^l where ``u`` written with ``digits`` significant digits is c·10^l."""
    if not (u > 0 and math.isfinite(u)):
        return math.nan
    return 0.5 * 10.0 ** (math.floor(math.log10(u)) - digits + 1)


def _quantile_mcse(chains: np.ndarray, prob: float) -> float:
    """Monte-Carlo standard error of the ``prob`` quantile of ``chains`` ``(chain, draw)`` (ArviZ, on the array:
    the same as on the InferenceData, without building a Dataset for each of the 48 calls of a summary)."""
    prob = min(max(prob, 1e-4), 1 - 1e-4)
    return float(az.mcse(chains, method="quantile", prob=prob))


def gum_statement(idata, name: str, hdi: tuple[float, float]) -> dict:
    """The GUM columns (:data:`GUM_COLUMNS`) of quantity ``name`` of ``idata``'s posterior, display units;
    ``hdi`` its shortest 95 % interval (from the summary)."""
    chains = np.asarray(idata.posterior[name].transpose("chain", "draw"))
    draws = chains.ravel()
    y, u = float(draws.mean()), float(draws.std(ddof=1))
    lo, hi = (float(v) for v in np.quantile(draws, [(1 - COVERAGE) / 2, (1 + COVERAGE) / 2]))
    probs = [(1 - COVERAGE) / 2, (1 + COVERAGE) / 2, float(np.mean(draws <= hdi[0])), float(np.mean(draws <= hdi[1]))]
    mcse = [_quantile_mcse(chains, p) for p in probs]
    tol = 2.0 * max(mcse)
    allowed = max(numerical_tolerance(u), 2.0 * max(mcse[:2]))
    miss = max(abs(y - K_GAUSSIAN * u - lo), abs(y + K_GAUSSIAN * u - hi))
    gaussian = miss <= allowed
    digits = next((d for d in (3, 2, 1) if numerical_tolerance(u, d) >= tol), 0)
    unit = units.SYMBOL[quantity_unit(name)]
    note = "" if gaussian else (
        f"not stated: y ± {K_GAUSSIAN:.2f}u misses the probabilistically symmetric 95 % interval by {miss:.2g} {unit}, "
        f"more than the numerical tolerance {allowed:.2g} {unit} (GUM-S1 §8): the posterior is not close enough "
        "to Gaussian, so only the coverage intervals are stated")
    return {"u": u, "ci95_shortest_low": float(hdi[0]), "ci95_shortest_high": float(hdi[1]),
            "ci95_symmetric_low": lo, "ci95_symmetric_high": hi, "coverage_probability": COVERAGE,
            "U": K_GAUSSIAN * u if gaussian else None, "k": K_GAUSSIAN if gaussian else None, "U_note": note,
            "n_draws": int(draws.size), "endpoint_tolerance": tol, "significant_digits": digits}


def gum_table(idata, summary: pd.DataFrame) -> pd.DataFrame:
    """:data:`GUM_COLUMNS` for every row of ``summary`` (which has ``hdi_low``, ``hdi_high``)."""
    rows = {n: gum_statement(idata, n, (r["hdi_low"], r["hdi_high"])) for n, r in summary.iterrows()}
    return pd.DataFrame.from_dict(rows, orient="index")[GUM_COLUMNS]


def _decimals(u: float, digits: int) -> int:
    return max(0, -(math.floor(math.log10(u)) - max(digits, 1) + 1)) if u > 0 and math.isfinite(u) else 2


def certificate_sentence(name: str, row, symbol: str | None = None) -> str:
    """One sentence in the form of a calibration certificate, from a summary row with the GUM columns.

    Values are rounded to the last digit of ``u`` at the significant digits the run supports (at most two).  A
    quantity that rests on the campaign's choice of reading (:mod:`.reading_choice`) gets a last sentence with its
    value under the alternative reading, marked †.
    """
    unit = units.SYMBOL[row["unit"]]
    d = _decimals(row["u"], min(int(row["significant_digits"]), DIGITS))

    def f(v):
        return f"{v:.{d}f}"

    who = f"{symbol} ({name})" if symbol else name
    text = f"{who} = {f(row['mean'])} {unit}, standard uncertainty u = {f(row['u'])} {unit}"
    if row["U"] is not None and row["U"] == row["U"]:
        text += (f", expanded uncertainty U = {f(row['U'])} {unit} (k = {row['k']:.2f}, coverage probability "
                 f"{100 * row['coverage_probability']:.0f} %, the posterior being close to Gaussian)")
    text += (f"; shortest {100 * row['coverage_probability']:.0f} % coverage interval [{f(row['ci95_shortest_low'])}, "
             f"{f(row['ci95_shortest_high'])}] {unit}, probabilistically symmetric [{f(row['ci95_symmetric_low'])}, "
             f"{f(row['ci95_symmetric_high'])}] {unit}. From {row['n_draws']:,} posterior draws (bulk ESS "
             f"{row['ess_bulk']:,.0f}); interval endpoints stable to ±{row['endpoint_tolerance']:.2g} {unit}")
    digits = int(row["significant_digits"])
    if digits == 1:
        text += ", enough to state u to one significant digit (two need a larger --target-ess)"
    elif digits < 1:
        text += (", not yet enough for GUM-S1 to state even one significant digit of u (a larger --target-ess "
                 "gives more)")
    return text + "." + alternative_clause(row, d)  # a value resting on a choice of reading says so
