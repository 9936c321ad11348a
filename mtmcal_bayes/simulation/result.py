"""``simulate``: the predicted eccentricities of a truth as a result object, and the synthetic campaign."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from .. import units
from ..campaign import Campaign, Truth
from ..io.campaign_writer import save_campaign
from ..machines.plugins import provided
from ..models import first_order_gap
from ..observations import Observations
from ..parameters import ParameterSpace, quantity_unit
from .simulate import (
    eccentricity_records,
    planned_as_runs,
    predict_truth,
    synthetic_campaign,
    truth_vector,
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
    probe_readings: list[dict] | None = None  # a described machine's: predicted probe readings, noise-free

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
        out = {"model": self.model, "eccentricities": eccentricity_records(self.observations, self.predicted)}
        if provided(self.campaign.machine, "simulate") is None:  # the engine's simulation: the machine and truth too
            out["machine"] = self.campaign.machine.description.builtin or self.campaign.machine.name
            out["truth"] = {n: units.from_internal(v, quantity_unit(n)) for n, v in self.truth.deviations.items()}
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
    """Predict every component for ``truth``; warn when the linear model is asked for a truth too large for it.  A
    campaign in a plug-in's own format is simulated by the plug-in (the thesis': :func:`thesis_simulation`)."""
    simulate = provided(campaign.machine, "simulate", _described_simulation)
    return simulate(campaign, truth, model=model, noise=noise, seed=seed, source=source)


def thesis_simulation(campaign: Campaign, truth: Truth, *, model: str, noise: bool, seed: int | None,
                      source: str) -> Simulation:
    """The simulation of a campaign in the thesis' format (its eccentricities; its probe readings when saved)."""
    obs, pred = predict_truth(campaign, truth, model, source=source)
    warnings = []
    if model == "linear":  # first order: say so when the truth is too large for it
        space = ParameterSpace.for_campaign(campaign)
        gap = first_order_gap(planned_as_runs(campaign), truth_vector(space, truth.ballbar_part(), source), space)
        if gap > campaign.ballbar.accuracy:
            warnings.append(f"the linear model is first order and this truth is too large for it: htm-thesis "
                            f"predicts eccentricities up to {units.from_internal(gap, 'um'):.1f} µm away (instrument "
                            f"accuracy {units.from_internal(campaign.ballbar.accuracy, 'um'):g} µm)")
    return Simulation(campaign, truth, source, model, obs, pred, noise, seed, warnings)


def _described_simulation(campaign: Campaign, truth: Truth, *, model: str, noise: bool, seed: int | None,
                          source: str) -> Simulation:
    """A described machine's simulation: its ball-bar eccentricities (if it has runs) and probe readings."""
    if campaign.ballbar.runs or campaign.ballbar.planned:  # planned runs are simulated (and written) too
        obs, pred = predict_truth(campaign, truth, model, source=source)
    else:
        obs, pred = Observations((), np.zeros(0), np.zeros(0), np.zeros(0, dtype=int)), np.zeros(0)
    readings = None
    if campaign.has_probe_readings():
        probe = synthetic_campaign(campaign, truth, model).probe
        readings = [{"run": r.id, "stylus": r.stylus, "position": i + 1,
                     **{f"{a}_deg": float(units.from_internal(v[i], "deg")) for a, v in r.angles.items()},
                     **{f"{x}_mm": float(r.centres[0, i, j]) for j, x in enumerate("XYZ")}}
                    for r in probe.runs for i in range(r.positions)]
    return Simulation(campaign, truth, source, model, obs, pred, noise, seed, [], probe_readings=readings)
