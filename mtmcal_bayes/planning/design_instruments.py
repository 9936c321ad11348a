"""The instruments a design chooses among (docs/design.md, "Every instrument"): the ball bar, the touch probe and the
R-test, each where the campaign has a set-up for it.

* the ball bar: ``[ballbar]`` set-ups (a tool length) — its catalogue (:mod:`.catalogue`);
* the touch probe: a ``[probe]`` with a repeatability, a stylus and a run giving the sphere — the probe catalogue
  (:mod:`.probe_catalogue`);
* the R-test: an ``[rtest]`` — the R-test catalogue (:mod:`.rtest_catalogue`).

Each instrument's rows carry its own discrepancy scale (the planner's: the rms of its prior).  The design's
σ-scale learnt from the data (its quantiles the criterion's nodes, its contraction the ``contraction`` goal) is the
ball bar's σ_model where the ball bar is among the instruments, else the first chosen instrument's.
"""

from __future__ import annotations

from ..errors import ParameterError
from .probe_catalogue import probe_catalogue, probe_feasibility
from .rtest_catalogue import rtest_catalogue, rtest_feasibility

#: the instruments a design may use, in the order a session measures them
INSTRUMENTS = ("ballbar", "probe", "rtest")
#: each instrument's discrepancy scale (the prior's name in ``[priors]``)
SCALE_OF = {"ballbar": "sigma_model", "probe": "sigma_model_probe", "rtest": "sigma_model_rtest"}
#: what a campaign lacks when it has no set-up for an instrument
_NEEDS = {"ballbar": "no [ballbar] set-up (a tool length, R_B_mm)",
          "probe": "no usable [probe] (a repeatability, a stylus and a run giving the sphere's position)",
          "rtest": "no [rtest] set-up (a nest, and a sphere)"}


def available(campaign) -> dict[str, bool]:
    """Whether ``campaign`` has a set-up for each instrument (:data:`INSTRUMENTS`)."""
    return {"ballbar": bool(campaign.ballbar.setups), "probe": bool(probe_catalogue(campaign)),
            "rtest": bool(rtest_catalogue(campaign))}


def parse_instruments(value) -> list[str] | None:
    """``"ballbar,probe"`` (or a list) as a list of instrument names, checked; None stays None (every available)."""
    if value is None:
        return None
    names = [n.strip() for n in (value.split(",") if isinstance(value, str) else value)]
    names = [n for n in names if n]
    if not names:
        raise ParameterError("instruments", f"expected one or more of {', '.join(INSTRUMENTS)}, got {value!r}")
    for n in names:
        if n not in INSTRUMENTS:
            raise ParameterError("instruments", f"unknown instrument {n!r} (expected one or more of "
                                 f"{', '.join(INSTRUMENTS)}, comma-separated)")
    return [n for n in INSTRUMENTS if n in names]


def chosen_instruments(campaign, value) -> list[str]:
    """The instruments of a design of ``campaign``: ``value`` (names, checked: each must have a set-up in the
    campaign) or, by default, every instrument the campaign has a set-up for."""
    names = parse_instruments(value)
    have = available(campaign)
    if names is None:
        out = [n for n in INSTRUMENTS if have[n]]
        if not out:
            raise ParameterError("instruments", "the campaign has a set-up for no instrument: give [ballbar] set-ups, "
                                 "a [probe] or an [rtest]")
        return out
    for n in names:
        if not have[n]:
            raise ParameterError("instruments", f"{n}: the campaign has {_NEEDS[n]}")
    return names


def other_candidates(campaign, instruments: list[str]) -> list:
    """The probe and R-test candidates of the chosen ``instruments``, within the travels."""
    out = []
    if "probe" in instruments:
        out += [c for c in probe_catalogue(campaign) if probe_feasibility(c, campaign)[0]]
    if "rtest" in instruments:
        out += [c for c in rtest_catalogue(campaign) if rtest_feasibility(c, campaign)[0]]
    return out


def taught(instruments: list[str]) -> str:
    """The instrument whose discrepancy scale the design learns and integrates out (module docstring)."""
    return instruments[0]


__all__ = ["INSTRUMENTS", "SCALE_OF", "available", "parse_instruments", "chosen_instruments", "other_candidates",
           "taught"]
