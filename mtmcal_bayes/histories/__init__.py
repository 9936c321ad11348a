"""A machine's calibration history: the posterior of every quantity at every date jointly, with a drift model
between dates, the changes that are real, and a forecast of when to recalibrate (docs/history.md).

* :class:`~.model.HistoryModel` — deviations as Gaussian random walks in time, each campaign with its own
  set-up offsets; exact linear-Gaussian system given the scales.
* :func:`fit_history` — sample the scales (emcee), condition the states, flag the changes, forecast.
"""

from __future__ import annotations

import math

from .. import units
from ..campaign import tolerance_text
from ..errors import MtmcalError
from ..parameters import quantity_unit
from .fit import PRACTICAL_MINIMUM, changes, check_history, check_temperatures, fit, recalibrate_by
from .kinematic import linearised_history
from .model import HistoryModel
from .quantities import history_quantities, instruments_in_words
from .result import HistoryResult, summary_frame

__all__ = ["HistoryModel", "HistoryResult", "fit_history"]


def fit_history(campaigns, *, model: str = "linear", seed: int = 1, tolerances: dict | None = None,
                thresholds: dict[str, float] | None = None, trend: str = "auto",
                data: str | None = None) -> HistoryResult:
    """The history of one machine from its campaigns (any order; each dated, one serial).

    ``tolerances``: ``{name: Tolerance}`` (default the latest campaign's ``[tolerances]``); ``thresholds``: the
    smallest change worth flagging per quantity, display units (default: a quarter of the tolerance's width
    where there is one, else :data:`~.fit.PRACTICAL_MINIMUM`).  ``trend``: ``"auto"`` (a drift rate per deviation
    where the data want it) or ``"off"`` (random walks only).  ``model``: ``linear``, or a kinematic model
    (``htm-thesis``, ``htm-literal``): each campaign is linearised at the history's estimate at its date and the
    linearisation checked against the nonlinear model (:func:`~.kinematic.linearised_history`).  ``data``: what each
    campaign's likelihood uses (default: every instrument it has, as ``sample``; the thesis machine: the ball bar),
    each instrument with its own discrepancy scale shared by the campaigns.
    """
    campaigns = sorted(campaigns, key=lambda c: c.date) if all(c.date for c in campaigns) else list(campaigns)
    check_history(campaigns)
    check_temperatures(campaigns)
    if model == "linear":
        hm, hf, check = HistoryModel(campaigns, model, data=data), None, None
    else:
        hm, hf, check = linearised_history(campaigns, model, seed=seed, trend=trend, data=data)
    names, left = tracked(campaigns, hm)
    if hf is None:
        hf = fit(hm, seed=seed, quantities=names, trend=trend)
    dates = [c.date for c in campaigns]
    tol = campaigns[-1].tolerances if tolerances is None else tolerances
    limits = {}
    for n, t in tol.items():
        if n in hf.quantities:
            unit = quantity_unit(n)
            limits[n] = (-math.inf if t.low is None else units.from_internal(t.low, unit),
                         math.inf if t.high is None else units.from_internal(t.high, unit))
    thr = {}
    for n in hf.quantities:
        lo, hi = limits.get(n, (-math.inf, math.inf))
        width = hi - lo
        thr[n] = (thresholds or {}).get(n, width / 4 if math.isfinite(width) else PRACTICAL_MINIMUM[quantity_unit(n)])
    found = changes(hf, dates, thr)
    forecast = [{"quantity": n, "recalibrate_by": recalibrate_by(hf, hf.quantities.index(n), lo, hi, last=dates[-1]),
                 "tolerance": tolerance_text(lo, hi, quantity_unit(n))} for n, (lo, hi) in limits.items()]
    # a tolerance on a quantity the history does not track: said, not dropped without a word
    unforecast = [{"quantity": n, "key": t.key, "why": "the campaigns do not determine it one by one: no forecast"}
                  for n, t in tol.items() if n not in hf.quantities]
    return HistoryResult(campaigns[-1].machine.serial, dates, [c.source for c in campaigns], summary_frame(hf, dates),
                         found, forecast, hf, limits, model=model, linearisation=check,
                         temperatures=[c.temperature_C for c in campaigns] if hm.thermal else None,
                         summary_20C=summary_frame(hf, dates, at_20C=True) if hm.thermal else None,
                         machine=machine_of(campaigns[-1]), not_determined=left, no_forecast=unforecast)


def tracked(campaigns, hm: HistoryModel) -> tuple[list[str], list[dict]]:
    """:func:`~.quantities.history_quantities` of ``hm``; none determined is an error naming the latest campaign."""
    names, left = history_quantities(campaigns, hm.posts, hm.deviations)
    if not names:
        raise MtmcalError(f"{campaigns[-1].source}: {instruments_in_words(campaigns, hm.posts)} of these campaigns "
                          "determines none of the machine's deviations one by one; a history needs at least one")
    return names, left


def machine_of(c) -> dict:
    """What a history says of its machine: ``{"type", "configuration", "description"}`` (``description``: the
    built-in type's name, "thesis" for the thesis machine, else "described")."""
    from ..machines.plugins import provided

    m = c.machine
    kind = provided(m, "description_key") or m.description.builtin or "described"
    return {"type": m.type, "configuration": m.configuration, "description": kind}
