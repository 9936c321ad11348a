"""Conformity with a tolerance, with the uncertainty taken into account (ISO 14253-1 decision rules).

For each quantity with a tolerance ``[low, high]`` (either end may be open):

* ``p_nonconformance``: the posterior probability that the quantity lies outside the tolerance, the
  share of the posterior draws outside it;
* ``conformity``: *conforms* when the shortest 95 % coverage interval lies inside the tolerance, *does not
  conform* when it lies wholly outside, *undecided* when it straddles a limit.  This is ISO 14253-1's rule
  with guard bands equal to the uncertainty: the estimate must lie inside the tolerance zone shrunk by the
  distance from the estimate to each end of its coverage interval (``acceptance_low``/``acceptance_high``,
  the acceptance zone) to prove conformity, and outside the zone widened the same way to prove
  nonconformity.  A verdict of *conforms* thus carries a probability of nonconformance of at most about
  2.5 % per open side, *does not conform* a probability of conformance of at most about 2.5 %.

A quantity the campaign's data do not determine one by one (the Jacobian's statement, the summary's
``identification``: ``"not identified"``, or ``"combination"`` where only a combination with others is determined)
gets no verdict: *not determined by the data*.  Its interval is its prior's (or the prior's share of a
combination), and a verdict on it would certify an assumption, not the machine; ``p_nonconformance`` is still
given, as what the prior says.
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from .. import units
from ..campaign import tolerance_text
from ..parameters import quantity_unit

CONFORMS, DOES_NOT_CONFORM, UNDECIDED = "conforms", "does not conform", "undecided"
NOT_DETERMINED = "not determined by the data"
#: the summary's ``identification`` of a quantity the data determine one by one
_DETERMINED = "data"
CONFORMITY_COLUMNS = ["tolerance_low", "tolerance_high", "p_nonconformance", "conformity", "acceptance_low",
                      "acceptance_high"]


def _verdict(a: float, b: float, low: float, high: float) -> str:
    if low <= a and b <= high:
        return CONFORMS
    if b < low or a > high:
        return DOES_NOT_CONFORM
    return UNDECIDED


def conformity_table(idata, summary: pd.DataFrame, tolerances: dict) -> pd.DataFrame:
    """:data:`CONFORMITY_COLUMNS` (display units: ″, µm) for each quantity of ``tolerances``
    (``{name: Tolerance}``, internal units) that ``summary`` reports; open ends are NaN."""
    rows = {}
    for name, tol in tolerances.items():
        if name not in summary.index:
            continue
        unit = quantity_unit(name)
        low = -math.inf if tol.low is None else units.from_internal(tol.low, unit)
        high = math.inf if tol.high is None else units.from_internal(tol.high, unit)
        draws = np.asarray(idata.posterior[name]).ravel()
        r = summary.loc[name]
        a, b, y = r["hdi_low"], r["hdi_high"], r["mean"]
        rows[name] = {"tolerance_low": low if tol.low is not None else math.nan,
                      "tolerance_high": high if tol.high is not None else math.nan,
                      "p_nonconformance": float(np.mean((draws < low) | (draws > high))),
                      "conformity": (_verdict(a, b, low, high)
                                     if r.get("identification", _DETERMINED) in (_DETERMINED, None) else NOT_DETERMINED),
                      "acceptance_low": low + (y - a) if tol.low is not None else math.nan,
                      "acceptance_high": high - (b - y) if tol.high is not None else math.nan}
    return pd.DataFrame.from_dict(rows, orient="index", columns=CONFORMITY_COLUMNS)


def row_tolerance_text(row, unit: str) -> str:
    """``±30″``, ``[-20, 50] µm`` or ``≤ 20″`` for a row of :func:`conformity_table`."""
    return tolerance_text(row["tolerance_low"], row["tolerance_high"], unit)
