"""Priors of the Bayesian analysis (SPEC §5): defaults with their reasons, campaign overrides.

Every prior is a :mod:`scipy.stats` distribution in internal units (mm, rad).
:class:`PriorSet` evaluates the joint log-density of a batch ``(n, q)`` with one
scipy call per distribution family, and gives each parameter a centre and a
width used to scale the sampling coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import stats

from .. import units

#: default prior of each kind of parameter: (dist, sd in display units, reason)
DEFAULTS = {
    "angle": ("normal", 60.0, "weakly informative: assembled machines are within tens of arc seconds"),
    "length": ("normal", 100.0, "weakly informative"),
    "xT": ("normal", 1.0, "the centring check adjusts the T ball to within ±1 µm (thesis Sec 4.2.2)"),
    "yT": ("normal", 1.0, "the centring check adjusts the T ball to within ±1 µm (thesis Sec 4.2.2)"),
    "zT": ("normal", 1.0, "the centring check adjusts the T ball to within ±1 µm (thesis Sec 4.2.2)"),
    "dRB": ("normal", 10.0, "dial-gauge tool-length measurement (thesis Sec 4.2.2)"),
    "xW": ("normal", 35.0, "the W ball shifts 10–60 µm in a random direction when clamped (thesis Sec 2.5.2)"),
    "yW": ("normal", 35.0, "the W ball shifts 10–60 µm in a random direction when clamped (thesis Sec 2.5.2)"),
    "zW": ("normal", 35.0, "the W ball shifts 10–60 µm in a random direction when clamped (thesis Sec 2.5.2)"),
    "sigma_model": ("halfnormal", 2.0, "dynamics, thermal drift and pitch error are not in the model"),
}


@dataclass(frozen=True)
class Prior:
    """Prior of one parameter, internal units.

    ``dist`` is ``"normal"`` (``loc``, ``scale`` = sd), ``"halfnormal"``
    (``scale``) or ``"uniform"`` (``loc`` = low, ``scale`` = high − low).
    """

    name: str
    dist: str
    loc: float
    scale: float
    unit: str
    reason: str

    def frozen(self):
        """The :mod:`scipy.stats` frozen distribution."""
        return {"normal": stats.norm, "halfnormal": stats.halfnorm, "uniform": stats.uniform}[self.dist](
            loc=self.loc, scale=self.scale)

    @property
    def sd(self) -> float:
        return float(self.frozen().std())

    @property
    def centre(self) -> float:
        """Centre of the sampling coordinate (mean, or 0 for half-normal)."""
        return 0.0 if self.dist == "halfnormal" else float(self.frozen().mean())

    def describe(self) -> str:
        d = lambda v: f"{units.from_internal(v, self.unit):g}"  # noqa: E731
        sym = units.SYMBOL[self.unit]
        if self.dist == "normal":
            return f"Normal({d(self.loc)}, {d(self.scale)} {sym})"
        if self.dist == "halfnormal":
            return f"HalfNormal({d(self.scale)} {sym})"
        return f"Uniform({d(self.loc)}, {d(self.loc + self.scale)} {sym})"


def make_prior(name: str, base: str, kind: str, overrides: dict[str, dict]) -> Prior:
    """The prior of parameter ``name`` (base name ``base``): campaign override, else default."""
    unit = "arcsec" if kind == "angle" else "um"
    if base in overrides:
        spec = overrides[base]
        reason = "set in the campaign's [priors]"
        if spec["dist"] == "uniform":
            return Prior(name, "uniform", spec["low"], spec["high"] - spec["low"], unit, reason)
        return Prior(name, spec["dist"], spec.get("mean", 0.0), spec["sd"], unit, reason)
    dist, sd, reason = DEFAULTS.get(base, DEFAULTS[kind])
    return Prior(name, dist, 0.0, units.to_internal(sd, unit), unit, reason)


class PriorSet:
    """Joint prior of independent parameters, vectorised over batches ``(n, q)``."""

    def __init__(self, priors: list[Prior]):
        self.priors = list(priors)
        self.names = [p.name for p in self.priors]
        self._groups = {}
        for dist, fam in (("normal", stats.norm), ("halfnormal", stats.halfnorm), ("uniform", stats.uniform)):
            idx = np.array([i for i, p in enumerate(self.priors) if p.dist == dist], dtype=int)
            if len(idx):
                self._groups[dist] = (fam, idx, np.array([self.priors[i].loc for i in idx]),
                                      np.array([self.priors[i].scale for i in idx]))
        self.centre = np.array([p.centre for p in self.priors])
        self.width = np.array([p.sd for p in self.priors])

    def logpdf(self, theta: np.ndarray) -> np.ndarray:
        """Joint log-density ``(n,)`` of a batch ``(n, q)`` (internal units); −inf outside the support."""
        theta = np.atleast_2d(theta)
        out = np.zeros(theta.shape[0])
        for fam, idx, loc, scale in self._groups.values():
            out += fam.logpdf(theta[:, idx], loc=loc, scale=scale).sum(axis=1)
        return out

    def rvs(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` independent draws, shape ``(n, q)``."""
        return np.column_stack([p.frozen().rvs(size=n, random_state=rng) for p in self.priors])
