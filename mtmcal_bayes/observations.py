"""The observation vector of a campaign: one entry per eccentricity component of each run.

Forward models predict exactly these entries, in this order, shape ``(n, m)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import units
from .conventions import machine_repeats, reported_values

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
    held: str = ""  # a described machine's run with other rotary axes held off zero: "A-45"
    reversed: bool = False  # its bar reversed (the T ball on the other side of the W ball)

    @property
    def label(self) -> str:
        how = "; ".join(x for x in ("reversed" if self.reversed else "", self.held) if x)
        return f"{self.component}_{self.pattern}{f'({how})' if how else ''}@{self.setup}/{self.mount}"


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

    #: the instrument these observations come from (its discrepancy scale: ``parameters.DISCREPANCY_SCALES``)
    instrument = "ballbar"

    @classmethod
    def from_campaign(cls, campaign) -> Observations:
        """One entry per component of every run, in the machine frame (each run read in its convention)."""
        keys, mean, sd, n = [], [], [], []
        for i, run in enumerate(campaign.ballbar.runs):
            held = ",".join(f"{a}{v:g}" for a, v in (run.hold_deg or {}).items() if v != 0)
            for comp, rep in machine_repeats(run, campaign.ballbar).items():
                keys.append(ObservationKey(i, run.pattern, run.setup, run.mount, comp, held, run.reversed))
                mean.append(float(np.mean(rep)))
                sd.append(float(np.std(rep, ddof=1)) if len(rep) > 1 else np.nan)
                n.append(len(rep))
        return cls(tuple(keys), np.array(mean), np.array(sd), np.array(n, dtype=int))

    def __len__(self) -> int:
        return len(self.keys)

    @property
    def labels(self) -> list[str]:
        return [k.label for k in self.keys]

    def noise_variance(self, accuracy: float) -> np.ndarray:
        """Variance of each mean without sigma_model, ``(m,)`` mm²: ``s²/n + accuracy²``.

        A component measured once takes the pooled repeat sd of the repeated ones
        (:meth:`pooled_sd`)."""
        repeated = self.n > 1
        return np.where(repeated, self.sd, self.pooled_sd()) ** 2 / self.n + accuracy**2

    def noise_components(self, accuracy: float) -> dict[str, np.ndarray]:
        """:meth:`noise_variance` by source, each ``(m,)`` mm²: ``"repeatability"`` (s²/n) and
        ``"instrument"`` (accuracy²); they sum to it."""
        total = self.noise_variance(accuracy)
        instrument = np.full(len(total), accuracy**2)
        return {"repeatability": total - instrument, "instrument": instrument}

    def pooled_sd(self) -> float:
        """Pooled repeat sd of the repeated components, mm; 0.25 µm when none was repeated."""
        repeated = self.n > 1
        if not repeated.any():
            return units.to_internal(TYPICAL_REPEAT_SD_UM, "um")
        return float(np.sqrt(np.sum((self.n[repeated] - 1) * self.sd[repeated] ** 2) / np.sum(self.n[repeated] - 1)))


def with_observations(campaign, values: np.ndarray):
    """A copy of ``campaign`` whose runs carry ``values`` instead of their measured repeats.

    ``values``: shape ``(m,)`` (one repeat each) or ``(m, r)`` (r repeats each),
    mm, machine frame, in the order of :meth:`Observations.from_campaign`; each run
    stores them as its reading convention reports them.  Published results
    are dropped (they belong to the measured data).
    """
    keys = Observations.from_campaign(campaign).keys
    values = [np.asarray(v, dtype=float).reshape(-1) for v in np.asarray(values, dtype=float)]
    if len(keys) != len(values):
        raise ValueError(f"expected {len(keys)} observations, got {len(values)}")
    return with_run_values(campaign, keys, values)


def with_run_values(campaign, keys, values):
    """A copy of ``campaign`` whose runs carry ``values`` (one ``(r,)`` array of machine-frame repeats, mm, per key
    of ``keys``) instead of their measured repeats, as each run's convention reports them; traces, published
    results and a choice of reading (``alternative_convention``: the values are written in the reading the run
    names, nothing was chosen) are dropped."""
    import copy

    out = copy.deepcopy(campaign)
    out.reported = {}
    out.ballbar.alternative_reason = ""
    for run in out.ballbar.runs:
        run.alternative_convention = None
    per_run: dict[int, dict[str, np.ndarray]] = {}
    for key, v in zip(keys, values):
        per_run.setdefault(key.run, {})[key.component] = np.asarray(v, dtype=float).copy()
    for i, machine in per_run.items():
        run = out.ballbar.runs[i]
        run.repeats = reported_values(run, out.ballbar, machine)
        run.trace_csv = None
    return out


@dataclass(frozen=True)
class ProbeKey:
    """Which touch-probe reading an observation is: ``run`` the run's id, ``stylus`` its stylus, ``angle_deg`` the
    value naming its position (the position's number, 1, 2, ...; a campaign format may name positions otherwise,
    with a key of its own: the thesis' by the indexed angle, degrees) and ``component`` (``X, Y, Z``; ``u1..u3``
    along the principal axes of a DPRNT fit's covariance)."""

    run: str
    stylus: str
    angle_deg: float
    component: str

    @property
    def group(self) -> str:
        """The reading group: one run with one stylus."""
        return f"probe {self.run}, stylus {self.stylus}"

    @property
    def label(self) -> str:
        return f"{self.component}@{self.run}#{self.angle_deg:g}/{self.stylus}"


@dataclass(frozen=True)
class ProbeObservations:
    """Touch-probe readings as observations: each sphere centre minus its nominal reading, mm.

    Attributes (``m`` = 3 per indexed position)
    -------------------------------------------
    keys : tuple of ProbeKey, length m
    mean : (m,) mean of the repeats minus the nominal reading, mm (rotated where the centre has a fit covariance)
    base_var : (m,) noise variance without sigma_model, mm²
    n : (m,) number of repeats
    """

    keys: tuple[ProbeKey, ...]
    mean: np.ndarray
    base_var: np.ndarray
    n: np.ndarray

    instrument = "probe"

    def __len__(self) -> int:
        return len(self.keys)

    @property
    def labels(self) -> list[str]:
        return [k.label for k in self.keys]

    def noise_variance(self, accuracy: float | None = None) -> np.ndarray:
        """Noise variance of each reading without sigma_model ``(m,)``, mm² (the probe's own)."""
        return self.base_var

    def noise_components(self, accuracy: float | None = None) -> dict[str, np.ndarray]:
        """:meth:`noise_variance` by source: all of it ``"probe readings"`` (repeat scatter or sphere fit)."""
        return {"probe readings": self.base_var}


@dataclass(frozen=True)
class RTestKey:
    """Which R-test reading an observation is: ``run`` the run's id, ``position`` its number from 1, ``component``
    the sensors' axis (``X, Y, Z``: the machine frame's at the home pose, carried as the run's frame says)."""

    run: str
    position: int
    component: str

    @property
    def group(self) -> str:
        """The reading group: one run."""
        return f"R-test {self.run}"

    @property
    def label(self) -> str:
        return f"{self.component}@{self.run}#{self.position}"


@dataclass(frozen=True)
class RTestObservations(ProbeObservations):
    """R-test readings as observations (SPEC §22): each position's mean displacement (sphere − nest), mm; ``keys``
    :class:`RTestKey`, ``base_var`` their noise variance without the discrepancy scale, ``n`` the repeats."""

    instrument = "rtest"

    def noise_components(self, accuracy: float | None = None) -> dict[str, np.ndarray]:
        """:meth:`noise_variance` by source: all of it ``"R-test readings"`` (repeat scatter, repeatability)."""
        return {"R-test readings": self.base_var}


@dataclass(frozen=True)
class JointObservations:
    """Ball-bar eccentricities followed by touch-probe readings: ``parts`` in order, one vector."""

    parts: tuple

    @property
    def keys(self) -> tuple:
        return tuple(k for p in self.parts for k in p.keys)

    @property
    def mean(self) -> np.ndarray:
        return np.concatenate([p.mean for p in self.parts])

    @property
    def labels(self) -> list[str]:
        return [lab for p in self.parts for lab in p.labels]

    def __len__(self) -> int:
        return sum(len(p) for p in self.parts)

    def noise_variance(self, accuracy: float) -> np.ndarray:
        return np.concatenate([p.noise_variance(accuracy) for p in self.parts])

    def noise_components(self, accuracy: float) -> dict[str, np.ndarray]:
        """The parts' noise sources over the joint vector (zero where a part lacks a source)."""
        parts = [p.noise_components(accuracy) for p in self.parts]
        names = list(dict.fromkeys(k for c in parts for k in c))
        return {k: np.concatenate([c.get(k, np.zeros(len(p))) for c, p in zip(parts, self.parts)]) for k in names}

    @property
    def instruments(self) -> list[str]:
        """The instrument of each observation, in order."""
        return [p.instrument for p in self.parts for _ in range(len(p))]

    def slices(self) -> list[tuple[object, slice]]:
        """Each part with its slice of the joint vector."""
        out, start = [], 0
        for p in self.parts:
            out.append((p, slice(start, start + len(p))))
            start += len(p)
        return out


def observation_instruments(observations) -> list[str]:
    """The instrument (``"ballbar"``, ``"probe"`` or ``"rtest"``) of each observation of ``observations`` (any of the three
    kinds), in order."""
    if isinstance(observations, JointObservations):
        return observations.instruments
    return [observations.instrument] * len(observations)
