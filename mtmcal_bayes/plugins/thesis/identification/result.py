"""Results of the thesis' deterministic identification, each value beside the published one."""

from __future__ import annotations

from dataclasses import dataclass, field

from .... import units
from ....campaign import ReportedValue
from ....iso import iso_symbol
from ....parameters import QUANTITIES


@dataclass
class Identified:
    """One recomputed quantity.

    ``value`` is in internal units (mm, rad), ``None`` when the data do not
    allow it (``missing`` says why).  ``reported`` is the published value, if any.
    """

    name: str
    value: float | None
    equation: str
    missing: str | None = None
    reported: ReportedValue | None = None
    note: str | None = None

    @property
    def unit(self) -> str:
        return QUANTITIES[self.name].unit

    @property
    def display(self) -> float | None:
        """Value in the display unit (″ or µm)."""
        return None if self.value is None else units.from_internal(self.value, self.unit)

    @property
    def reported_display(self) -> float | None:
        return None if self.reported is None else units.from_internal(self.reported.value, self.reported.unit)

    @property
    def difference(self) -> float | None:
        """Recomputed minus reported, display unit."""
        if self.value is None or self.reported is None:
            return None
        return self.display - self.reported_display

    @property
    def reproduced(self) -> bool | None:
        """Whether the recomputed value rounds to the printed one (``None`` if nothing to compare)."""
        if self.difference is None:
            return None
        half_step = 0.5 * 10.0 ** (-self.reported.decimals)
        return abs(self.difference) <= half_step * (1 + 1e-9)

    def to_json(self) -> dict:
        d = {"value": self.display, "unit": self.unit, "equation": self.equation}
        if self.missing:
            d["missing"] = self.missing
        if self.reported is not None:
            d.update(reported=self.reported_display, difference=self.difference, reproduced=self.reproduced)
        if self.note:
            d["note"] = self.note
        return d


@dataclass
class IdentificationResult:
    """Recomputed ball-bar and probe values, thesis consistency checks and stated assumptions."""

    ballbar: dict[str, Identified]
    probe: dict[str, Identified]
    checks: list[str] = field(default_factory=list)
    assumptions: list[str] = field(default_factory=list)
    source: str = ""
    #: the same ball-bar equations on the offsets read in the campaign's convention, where that reading differs from
    #: the thesis' (``None`` otherwise), and the convention in words
    ballbar_in_convention: dict[str, Identified] | None = None
    convention: str = "thesis"
    #: sentences naming the probe sections the campaign lacks and the probe values that costs
    missing_probe: list[str] = field(default_factory=list)

    def to_json(self) -> dict:
        out = {
            "campaign": self.source,
            "ballbar": {k: {**v.to_json(), "iso": iso_symbol(k)} for k, v in self.ballbar.items()},
            "probe": {k: {**v.to_json(), "iso": iso_symbol(k)} for k, v in self.probe.items()},
            "checks": self.checks,
            "assumptions": self.assumptions,
            "convention": self.convention,
        }
        if self.ballbar_in_convention is not None:
            out["ballbar_in_convention"] = {k: {**v.to_json(), "iso": iso_symbol(k)}
                                            for k, v in self.ballbar_in_convention.items()}
        return out

    def references(self) -> dict[str, dict[str, float | None]]:
        """The values to set beside a posterior (:func:`~mtmcal_bayes.posterior.comparison.comparison`), display
        units, by kind then quantity: ``ballbar`` (Eqs 4.10–4.18 on the offsets read as the campaign reads them, the
        data the posterior saw; the thesis' own reading is :attr:`ballbar`), ``probe_reported`` (Table 5.3, where
        printed) and ``probe_recomputed`` (Eqs 5.1–5.19).  Every quantity a method addresses has an entry, ``None``
        where it gives no value."""
        ballbar = self.ballbar_in_convention if self.ballbar_in_convention is not None else self.ballbar
        return {"ballbar": {n: v.display for n, v in ballbar.items()},
                "probe_reported": {n: v.reported_display if v.reported else None for n, v in self.probe.items()},
                "probe_recomputed": {n: v.display for n, v in self.probe.items()}}

    def to_text(self) -> str:
        """What ``mtmcal-bayes identify`` prints."""
        from .output import format_identification

        return format_identification(self)

    def table(self, which: str = "ballbar"):
        """The ``ballbar`` or ``probe`` values as a table, one row per quantity (recomputed and published value in
        display units, difference, flag): what the report shows and writes as ``identification_<which>.csv``."""
        from .output import identification_table

        return identification_table(getattr(self, which))
