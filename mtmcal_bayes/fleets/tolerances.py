"""A fleet's tolerances: a plant-wide set applied to every machine, and conformity decided on a shown estimate.

* ``fleet --tolerances FILE`` (``mb.fleet(tolerances=...)``): one ``[tolerances]`` set (the file format of
  ``sample --tolerances``, :func:`~mtmcal_bayes.io.tolerances.load_tolerances`) instead of each campaign's own:
  each campaign's conformity, each history's forecast and change thresholds.  It is a setting of the fleet
  (:class:`~.units.FleetSettings`), kept as a hashable, JSON-able tuple, and enters every unit's cache key.
* :func:`machine_tolerances`: the set as one machine names its quantities (an ISO 230-7 symbol or an alias such as
  a thesis name, :func:`~mtmcal_bayes.io.tolerances.resolve_tolerances`), and the names it gives that the machine
  does not have: a machine of another type is not flagged for them, and the overview says so.
* :func:`estimate_conformity`: the overview shows a machine's *history* estimate at its latest date, mean and sd;
  its conformity is decided on that estimate, taken as normal (what the overview says it does).
"""

from __future__ import annotations

import math

from .. import units
from ..campaign import Tolerance
from ..errors import ParameterError
from ..io.tolerances import resolve_tolerances
from ..parameters import quantity_unit
from ..posterior.conformity import CONFORMS, DOES_NOT_CONFORM, UNDECIDED

#: the coverage factor of the interval a history estimate's verdict is decided on (95 % of a normal)
K_95 = 1.959963984540054


def tolerance_tuple(spec) -> tuple:
    """``((name, low, high), ...)`` in the order given (a file's: an error names the later of two keys), names as
    written, internal units (None an open end), from ``{name: Tolerance}`` (what
    :func:`~mtmcal_bayes.io.tolerances.load_tolerances` reads) or from such a tuple; anything else, or a tolerance
    that is not one of a quantity known by its name, is a :class:`~mtmcal_bayes.errors.ParameterError` of
    ``tolerances``."""
    if isinstance(spec, dict):
        items = list(spec.items())
    elif isinstance(spec, (tuple, list)) and all(isinstance(t, (tuple, list)) and len(t) == 3 for t in spec):
        items = [(t[0], tuple(t)) for t in spec]
    else:
        raise ParameterError("tolerances", f"expected a [tolerances] file or {{name: Tolerance}}, got "
                             f"{type(spec).__name__}")
    out = []
    for name, t in items:
        low, high = (t.low, t.high) if isinstance(t, Tolerance) else t[1:] if isinstance(t, tuple) else (0.0, 0.0)
        ends = [v for v in (low, high) if v is not None]
        if _unit_of(name) is None or not ends or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                         and math.isfinite(v) for v in ends) \
                or (low is not None and high is not None and not low < high):
            raise ParameterError("tolerances", f"{name}: {t!r} is not a tolerance of a quantity "
                                 "(Tolerance(name, low, high) with low < high, internal units)")
        out.append((name, None if low is None else float(low), None if high is None else float(high)))
    return tuple(out)


def _unit_of(name) -> str | None:
    """The unit of a quantity known by its name alone (a thesis name or an ISO symbol), else None."""
    try:
        return quantity_unit(name) if isinstance(name, str) else None
    except KeyError:
        return None


def tolerance_dict(spec: tuple, source: str = "") -> dict[str, Tolerance]:
    """``{name: Tolerance}`` of a :func:`tolerance_tuple`, each with the key it is written with in ``source`` (the
    file it was read from, "" for one made in Python)."""
    return {n: Tolerance(n, lo, hi, f"tolerances.{n}_{quantity_unit(n)}", source) for n, lo, hi in spec}


def machine_tolerances(spec: tuple | None, machine, source: str = "") -> tuple[dict[str, Tolerance] | None, list[str]]:
    """``({name: Tolerance}, not_here)``: the plant-wide :func:`tolerance_tuple` ``spec`` by the quantity names of
    ``machine`` (a :class:`~mtmcal_bayes.campaign.Machine`) and, sorted, the names it gives that the machine does not
    have (left out: not decided for this machine).  Two names of one quantity of the machine are an
    :class:`~mtmcal_bayes.errors.InputError` of ``source`` (a :class:`ParameterError` without one).  None: None."""
    if spec is None:
        return None, []
    resolved, missing = resolve_tolerances(tolerance_dict(spec, source), machine, strict=False)
    return resolved, sorted(missing)


def display_limits(tolerances: dict) -> dict[str, dict]:
    """``{name: {"low", "high"}}`` in display units (″, µm; None an open end) of ``{name: Tolerance}``."""
    return {n: {"low": None if t.low is None else units.from_internal(t.low, quantity_unit(n)),
                "high": None if t.high is None else units.from_internal(t.high, quantity_unit(n))}
            for n, t in sorted(tolerances.items())}


def _phi(x: float) -> float:
    return 0.5 * math.erfc(-x / math.sqrt(2.0))


def estimate_conformity(mean: float, sd: float, low: float | None, high: float | None) -> tuple[str, float]:
    """Verdict and P(outside) of an estimate taken as normal N(mean, sd²) against ``[low, high]`` (display units,
    None an open end): P = Φ((low − mean)/sd) + Φ((mean − high)/sd); *conforms* when mean ± 1.96·sd lies inside
    the tolerance, *does not conform* when it lies wholly outside, *undecided* when it straddles a limit (the
    ISO 14253-1 rule a campaign's verdict follows, its 95 % interval that of the normal)."""
    lo = -math.inf if low is None else low
    hi = math.inf if high is None else high
    sd = max(sd, 1e-300)
    p = (_phi((lo - mean) / sd) if math.isfinite(lo) else 0.0) + (_phi((mean - hi) / sd) if math.isfinite(hi) else 0.0)
    a, b = mean - K_95 * sd, mean + K_95 * sd
    verdict = CONFORMS if lo <= a and b <= hi else DOES_NOT_CONFORM if b < lo or a > hi else UNDECIDED
    return verdict, min(p, 1.0)
