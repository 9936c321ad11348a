"""``simulate``: the predicted eccentricities of a truth as a result object, and the synthetic campaign."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .. import units
from ..campaign import Campaign, Truth
from ..io.campaign_writer import save_campaign
from ..observations import Observations
from ..parameters import quantity_unit
from .simulate import (
    ballbar_prediction,
    eccentricity_records,
    first_order_warnings,
    probe_readings,
    probe_records,
    synthetic_campaign,
)


@dataclass
class Simulation:
    """Noise-free eccentricities ``predicted`` (m,), mm, of every observed component of ``campaign``
    under ``model`` for ``truth``; ``noise``/``seed`` say how :meth:`synthetic_campaign` scatters them."""

    campaign: Campaign
    truth: Truth
    truth_source: str
    model: str
    observations: Observations
    predicted: np.ndarray
    noise: bool = False
    seed: int | None = None
    warnings: list[str] = field(default_factory=list)
    output: str | None = None
    probe_readings: list[dict] | None = None  # JSON records of the probe model's readings, noise-free (probe_records)

    @property
    def eccentricities(self) -> pd.DataFrame:
        """One row per component: pattern, setup, mount, component, value_um."""
        return pd.DataFrame(eccentricity_records(self.observations, self.predicted))

    def synthetic_campaign(self) -> Campaign:
        """A copy of the campaign whose runs carry the simulated data and whose ``[truth]`` is the truth."""
        return synthetic_campaign(self.campaign, self.truth, self.model, noise=self.noise, seed=self.seed)

    def describe_noise(self) -> str:
        return f"with noise (seed {self.seed})" if self.noise else "noise-free"

    def save(self, path) -> None:
        """Write :meth:`synthetic_campaign` as a campaign TOML with a header saying how it was made."""
        dropped = self.campaign.probe_gap() if self.campaign.has_probe_readings() else None
        header = (f"Synthetic campaign simulated by mtmcal-bayes with model {self.model}, {self.describe_noise()},\n"
                  f"from {self.campaign.source} and truth {self.truth_source}.")
        if dropped is not None:
            skipped = dropped.skipped("The simulation of the touch-probe readings (no [probe] written)")
            header += "\n" + skipped
            self.warnings.append(skipped)
        save_campaign(self.synthetic_campaign(), path, header=header)
        self.output = str(path)

    def to_json(self) -> dict:
        machine = self.campaign.machine
        out = {"model": self.model, "eccentricities": eccentricity_records(self.observations, self.predicted),
               "machine": getattr(machine.description, "builtin", None) or machine.name,
               "truth": {n: units.from_internal(v, quantity_unit(n)) for n, v in self.truth.deviations.items()}}
        if self.probe_readings is not None:
            out["probe"] = self.probe_readings
        return out

    def to_text(self) -> str:
        if self.output:
            return (f"wrote {self.output}: {len(self.observations)} eccentricity components, {self.describe_noise()}, "
                    f"model {self.model}")
        lines = [f"Predicted eccentricities (µm), model {self.model}, truth {self.truth_source}"]
        for rec in eccentricity_records(self.observations, self.predicted):
            lines.append(f"  {rec['pattern']:2s} {rec['setup']:>6s} {rec['mount']:>4s}  {rec['component']}  "
                         f"{rec['value_um']:10.3f}")
        return "\n".join(lines)


def simulate_truth(campaign: Campaign, truth: Truth, *, model: str = "htm-thesis", noise: bool = False,
                   seed: int | None = None, source: str = "<truth>") -> Simulation:
    """The eccentricities of every measured and planned ball-bar run for ``truth`` (with a warning where the linear
    model is asked for a truth too large for it) and the probe model's readings of every probed position, on any
    machine.  A campaign with no runs and neither probe nor R-test readings is an error (nothing to simulate); the
    R-test's readings are written by :meth:`Simulation.save` (its synthetic campaign)."""
    bb = campaign.ballbar
    if bb.runs or bb.planned or not (campaign.has_probe_readings() or campaign.has_rtest_readings()):
        fm, theta, pred = ballbar_prediction(campaign, truth, model, source=source)
        obs, warnings = fm.observations, first_order_warnings(fm, theta)
    else:  # a campaign of the probe or the R-test alone (none of the three: ballbar_prediction says so)
        obs, pred, warnings = Observations((), np.zeros(0), np.zeros(0), np.zeros(0, dtype=int)), np.zeros(0), []
    readings = probe_readings(campaign, truth, model)
    records = probe_records(campaign, readings) if readings is not None else None
    return Simulation(campaign, truth, source, model, obs, pred, noise, seed, warnings, probe_readings=records)
