"""The observation vector of a campaign: one entry per eccentricity component of each run.

Forward models predict exactly these entries, in this order, shape ``(n, m)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: typical repeat scatter of one eccentricity component, µm (thesis Table 4.4: 0.05–0.54 µm, typically 0.25):
#: the repeat sd assumed where a campaign gives none, and that of simulated repeats
TYPICAL_REPEAT_SD_UM = 0.25


@dataclass(frozen=True)
class ObservationKey:
    """Which run and component an observation is: ``run`` indexes ``campaign.ballbar.runs``."""

    run: int
    pattern: str
    setup: str
    mount: str
    component: str  # "ex", "ey" or "ez"

    @property
    def label(self) -> str:
        return f"{self.component}_{self.pattern}@{self.setup}/{self.mount}"


@dataclass(frozen=True)
class Observations:
    """Observed eccentricities of a campaign.

    Attributes (``m`` observations)
    -------------------------------
    keys : tuple of ObservationKey, length m
    mean : (m,) mean of the repeats, mm
    sd : (m,) sample standard deviation of the repeats (ddof = 1), mm; NaN for a single repeat
    n : (m,) number of repeats
    """

    keys: tuple[ObservationKey, ...]
    mean: np.ndarray
    sd: np.ndarray
    n: np.ndarray

    @classmethod
    def from_campaign(cls, campaign) -> Observations:
        keys, mean, sd, n = [], [], [], []
        for i, run in enumerate(campaign.ballbar.runs):
            for comp, rep in run.repeats.items():
                keys.append(ObservationKey(i, run.pattern, run.setup, run.mount, comp))
                mean.append(float(np.mean(rep)))
                sd.append(float(np.std(rep, ddof=1)) if len(rep) > 1 else np.nan)
                n.append(len(rep))
        return cls(tuple(keys), np.array(mean), np.array(sd), np.array(n, dtype=int))

    def __len__(self) -> int:
        return len(self.keys)

    @property
    def labels(self) -> list[str]:
        return [k.label for k in self.keys]


def with_observations(campaign, values: np.ndarray):
    """A copy of ``campaign`` whose runs carry ``values`` instead of their measured repeats.

    ``values``: shape ``(m,)`` (one repeat each) or ``(m, r)`` (r repeats each),
    mm, in the order of :meth:`Observations.from_campaign`.  Published results
    are dropped (they belong to the measured data).
    """
    import copy

    values = np.asarray(values, dtype=float)
    if values.ndim == 1:
        values = values[:, None]
    out = copy.deepcopy(campaign)
    out.reported = {}
    keys = Observations.from_campaign(campaign).keys
    if len(keys) != len(values):
        raise ValueError(f"expected {len(keys)} observations, got {len(values)}")
    for key, v in zip(keys, values):
        out.ballbar.runs[key.run].repeats[key.component] = v.copy()
    return out
