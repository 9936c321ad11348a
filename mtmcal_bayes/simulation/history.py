"""Synthetic calibration histories: one machine calibrated again and again while its deviations drift.

A history is a series of campaigns of one machine (one ``[machine] serial``), each a copy of a base
campaign with its own ``date``, its own data simulated from the truth *at that date*, and fresh set-up
offsets: the W ball is clamped anew (mount offsets ``xW, yW, zW`` drawn from their priors), the T ball
re-centred (``xT, yT, zT, dRB`` drawn from theirs).  The truth drifts by :class:`Drift` terms: a step
(a crash, a repair) or a ramp (wear, settling) in chosen quantities.
"""

from __future__ import annotations

import copy
import datetime
from dataclasses import dataclass

import numpy as np

from .. import units
from ..campaign import REFERENCE_TEMPERATURE_C, Campaign, Truth
from ..errors import ParameterError
from ..inference.priors import make_prior
from ..machines.plugins import provided
from ..parameters import DEVIATIONS, MOUNT_NUISANCE, SETUP_NUISANCE, quantity_unit
from .simulate import synthetic_campaign

DRIFT_KINDS = ("step", "ramp")
DAYS_PER_YEAR = 365.25


@dataclass(frozen=True)
class Drift:
    """A change of one deviation over time, internal units: ``"step"`` adds ``size`` from ``start`` on;
    ``"ramp"`` adds ``size`` per year of time after ``start``.  ``quantity``: a deviation of the machine (checked
    by :func:`drift_from_display` against the machine's names)."""

    quantity: str
    kind: str
    size: float
    start: datetime.datetime

    def __post_init__(self):
        if self.kind not in DRIFT_KINDS:
            raise ParameterError("drift", f"{self.kind!r} (expected {' or '.join(DRIFT_KINDS)})")

    def offset(self, when: datetime.datetime) -> float:
        """What the drift adds at ``when``, internal units."""
        if when < self.start:
            return 0.0
        if self.kind == "step":
            return self.size
        return self.size * (when - self.start).total_seconds() / (86400.0 * DAYS_PER_YEAR)


def drift_from_display(quantity: str, kind: str, size: float, start: datetime.datetime, *, names=None) -> Drift:
    """A :class:`Drift` with ``size`` in display units (″ or µm; per year for a ramp).  ``names``: the machine's
    deviations (default the thesis machine's, :func:`deviation_names`)."""
    _check_deviation(quantity, "drift", names)
    return Drift(quantity, kind, units.to_internal(size, quantity_unit(quantity)), start)


def deviation_names(campaign: Campaign | None = None) -> list[str]:
    """The deviations a drift or a thermal sensitivity may name: the machine's plug-in's names where it has them (the
    thesis machine's; also without a campaign), else every location error its description generates (ISO 230-7)."""
    if campaign is None:
        return list(DEVIATIONS)
    names = provided(campaign.machine, "deviation_table")
    if names is not None:
        return list(names)
    from ..machines.deviations import generated

    return [d.name for d in generated(campaign.machine.description)]


def _check_deviation(quantity: str, parameter: str, names) -> None:
    names = list(DEVIATIONS) if names is None else list(names)
    if quantity not in names:
        raise ParameterError(parameter, f"{quantity!r} is not a deviation of the machine (one of {', '.join(names)})")


def truth_at(truth: Truth, drifts, when: datetime.datetime) -> dict[str, float]:
    """The deviations of ``truth`` at ``when`` with every drift applied, internal units."""
    dev = dict(truth.deviations)
    for d in drifts:
        dev[d.quantity] = dev.get(d.quantity, 0.0) + d.offset(when)
    return dev


def _offset_priors(campaign: Campaign) -> dict:
    """The frozen prior of each set-up and mount offset (by base name): made once per history, not per draw (a
    scipy distribution takes longer to make than to draw from)."""
    return {b: make_prior(b, b, table[b].kind, campaign.priors).frozen()
            for table in (SETUP_NUISANCE, MOUNT_NUISANCE) for b in table}


def _fresh_offsets(campaign: Campaign, rng: np.random.Generator, priors: dict) -> tuple[dict, dict]:
    """Set-up offsets of a new campaign drawn from their priors (:func:`_offset_priors`): per tool setup and per
    W-ball mount."""
    setups = {s: {b: float(priors[b].rvs(random_state=rng)) for b in SETUP_NUISANCE} for s in campaign.ballbar.setups}
    mounts = {m: {b: float(priors[b].rvs(random_state=rng)) for b in MOUNT_NUISANCE} for m in campaign.ballbar.mounts}
    return setups, mounts


def thermal_from_display(quantity: str, per_degree: float, names=None) -> tuple[str, float]:
    """A thermal sensitivity ``(deviation, internal units per °C)`` from display units (″ or µm per °C)."""
    _check_deviation(quantity, "thermal", names)
    return quantity, units.to_internal(per_degree, quantity_unit(quantity))


def synthetic_history(campaign: Campaign, truth: Truth, dates, *, drifts=(), serial: str = "SIM-001",
                      model: str = "linear", seed: int = 0, temperatures=None, thermal=(),
                      sigma_model: float = 0.0) -> list[Campaign]:
    """One campaign per date (datetimes, increasing): data simulated (with noise) from ``truth`` plus ``drifts``
    at that date, fresh set-up offsets each time, ``[machine] serial`` = ``serial``.  Seeded: the same seed
    gives the same history.

    ``temperatures``: the workshop temperature of each campaign (°C, recorded as its ``temperature_C``);
    ``thermal``: ``(deviation, sensitivity)`` pairs (internal units per °C, :func:`thermal_from_display`): the
    deviation is measured at ``truth + sensitivity·(temperature − 20 °C)``.  ``sigma_model`` (mm): the machine's
    model discrepancy (:func:`~.simulate.synthetic_campaign`)."""
    dates = list(dates)
    if any(b <= a for a, b in zip(dates, dates[1:])):
        raise ParameterError("dates", "the campaign dates must increase")
    if temperatures is not None and len(temperatures) != len(dates):
        raise ParameterError("temperatures", f"{len(temperatures)} temperatures for {len(dates)} campaigns")
    if thermal and temperatures is None:
        raise ParameterError("thermal", "a thermal sensitivity needs the campaigns' temperatures")
    rng = np.random.default_rng(seed)
    priors = _offset_priors(campaign)
    out = []
    for i, when in enumerate(dates):
        setups, mounts = _fresh_offsets(campaign, rng, priors)
        dev = truth_at(truth, drifts, when)
        for name, k in thermal:
            dev[name] = dev.get(name, 0.0) + k * (temperatures[i] - REFERENCE_TEMPERATURE_C)
        t = Truth(dev, setups, mounts, copy.deepcopy(truth.probe), copy.deepcopy(truth.rtest))
        c = synthetic_campaign(campaign, t, model, noise=True, seed=int(rng.integers(2**31)), sigma_model=sigma_model)
        c.reported = {}
        c.date = when
        c.temperature_C = None if temperatures is None else float(temperatures[i])
        c.machine = copy.copy(c.machine)
        c.machine.serial = serial
        out.append(c)
    return out


class SimulatedHistory(list):
    """The campaigns of a simulated history (a list of Campaigns, by date) and ``truth_source``: where the truth
    they were simulated from came from (a file, the campaign's ``[truth]``, its posterior mean)."""

    def __init__(self, campaigns=(), *, truth_source: str = ""):
        super().__init__(campaigns)
        self.truth_source = truth_source


def history_dates(n: int, every_days: float, start=None) -> list[datetime.datetime]:
    """``n`` campaign dates ``every_days`` apart from ``start`` (a date; default 2026-01-05)."""
    if not (isinstance(every_days, (int, float)) and 1 <= every_days <= 3650):
        raise ParameterError("every_days", f"{every_days}: campaigns 1 to 3650 days apart")
    t0 = start or datetime.date(2026, 1, 5)
    t0 = datetime.datetime(t0.year, t0.month, t0.day)
    return [t0 + datetime.timedelta(days=every_days * i) for i in range(n)]


def parse_drift(spec, kind: str, dates, names=None) -> Drift:
    """A :class:`Drift` from ``"NAME=SIZE@K"`` (display units; from the K-th of ``dates`` on), or a Drift as is.
    ``kind``: ``"step"`` or ``"ramp"`` (the parameter an error names: ``steps`` / ``ramps``); ``names``: the
    machine's deviations (:func:`deviation_names`)."""
    if isinstance(spec, Drift):
        return spec
    parameter = f"{kind}s"
    try:
        name, rest = spec.split("=")
        size, k = rest.split("@")
        size, k = float(size), int(k)
    except ValueError:
        raise ParameterError(parameter, f"{spec!r}: expected NAME=SIZE@K, e.g. beta_CZ=40@4") from None
    if not 1 <= k <= len(dates):
        raise ParameterError(parameter, f"{spec!r}: K = {k} is not a campaign number (1 to {len(dates)})")
    return drift_from_display(name.strip(), kind, size, dates[k - 1], names=names)


def parse_thermal(spec, names=None) -> tuple[str, float]:
    """A thermal sensitivity ``(deviation, internal units per °C)`` from ``"NAME=K"`` (″ or µm per °C), or as is."""
    if not isinstance(spec, str):
        return spec
    try:
        name, k = spec.split("=")
        return thermal_from_display(name.strip(), float(k), names)
    except ValueError:
        raise ParameterError("thermal", f"{spec!r}: expected NAME=K (″ or µm per °C), e.g. alpha_XB=1.5") from None
