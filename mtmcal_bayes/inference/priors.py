"""Priors of the Bayesian analysis (SPEC §5): defaults with their reasons, campaign overrides, learnt σ_model priors.

Every prior is a :mod:`scipy.stats` distribution in internal units (mm, rad)
(:meth:`Prior.frozen`: draws, quantiles, moments).  In the sampler's hot loop
:class:`PriorSet` evaluates the joint log-density of a batch ``(n, q)`` in plain
numpy, one expression per distribution family (the tests hold it to
``scipy.stats``), and gives each parameter a centre and a width used to scale
the sampling coordinates.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .. import units

_LOG_SQRT_2PI = 0.5 * math.log(2.0 * math.pi)

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
    "xS": ("normal", 10.0, "stylus ball centred on the spindle axis to ~10 µm (probe on-centre adjustment)"),
    "yS": ("normal", 10.0, "stylus ball centred on the spindle axis to ~10 µm (probe on-centre adjustment)"),
    "zS": ("normal", 10.0, "stylus ball centred on the spindle axis to ~10 µm (probe on-centre adjustment)"),
    "zP": ("normal", 300.0, "sphere placed on the table by hand: a few hundred µm"),
    "dRS": ("normal", 10.0, "stylus length from a tool setter, like the ball bar's dRB"),
    "rS": ("normal", 5.0, "effective radius after calibration on a reference: pre-travel leaves a few µm"),
    "xP": ("normal", 300.0, "sphere placed on the table by hand: a few hundred µm"),
    "yP": ("normal", 300.0, "sphere placed on the table by hand: a few hundred µm"),
    "xD": ("normal", 1000.0, "broad: where the sphere sits in the reading frame is not stated"),
    "yD": ("normal", 1000.0, "broad: where the sphere sits in the reading frame is not stated"),
    "zD": ("normal", 1000.0, "broad: where the sphere sits in the reading frame is not stated"),
    "sigma_model": ("halfnormal", 2.0, "dynamics, thermal drift and pitch error are not in the model"),
    "sigma_model_probe": ("halfnormal", 2.0, "thermal drift between indexed positions, stylus bending and pre-travel "
                          "lobing are not in the probe model"),
    "xZR": ("normal", 1000.0, "broad: the sensors were zeroed at the run's first position, wherever the sphere was"),
    "yZR": ("normal", 1000.0, "broad: the sensors were zeroed at the run's first position, wherever the sphere was"),
    "zZR": ("normal", 1000.0, "broad: the sensors were zeroed at the run's first position, wherever the sphere was"),
    "sigma_model_rtest": ("halfnormal", 2.0, "thermal drift between positions, sensor non-linearity and the sphere's "
                          "form are not in the R-test model"),
}
#: the R-test's placement and nest terms take the prior sds its ``[rtest]`` states (SPEC §22; ``stated`` of
#: :func:`make_prior`), normal about zero
STATED_REASON = "stated in the campaign's [rtest] (its default where not given, SPEC §22)"


@dataclass(frozen=True)
class Prior:
    """Prior of one parameter, internal units.

    ``dist`` is ``"normal"`` (``loc``, ``scale`` = sd), ``"halfnormal"``
    (``scale``), ``"uniform"`` (``loc`` = low, ``scale`` = high − low) or
    ``"lognormal"`` (``scale`` = median, ``shape`` = sd of ln x; a σ_model learnt elsewhere).
    """

    name: str
    dist: str
    loc: float
    scale: float
    unit: str
    reason: str
    shape: float = 0.0

    def frozen(self):
        """The :mod:`scipy.stats` frozen distribution (made once)."""
        return self._frozen

    def draw(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` draws ``(n,)``: the frozen distribution's ``rvs(size=n, random_state=rng)``, the same numbers;
        a normal prior's without making the scipy distribution (a design's check draws hundreds of parameters)."""
        if self.dist == "normal":
            return rng.standard_normal(n) * self.scale + self.loc  # scipy's norm.rvs, operation by operation
        return self.frozen().rvs(size=n, random_state=rng)

    @functools.cached_property
    def _frozen(self):
        if self.dist == "lognormal":
            return stats.lognorm(s=self.shape, loc=self.loc, scale=self.scale)
        return {"normal": stats.norm, "halfnormal": stats.halfnorm, "uniform": stats.uniform}[self.dist](
            loc=self.loc, scale=self.scale)

    @functools.cached_property
    def sd(self) -> float:
        """Standard deviation, in closed form (the scipy distribution's ``std()``; tests hold them equal)."""
        if self.dist == "normal":
            return float(self.scale)
        if self.dist == "halfnormal":
            return float(self.scale * math.sqrt(1.0 - 2.0 / math.pi))
        if self.dist == "lognormal":
            return float(self.scale * math.exp(0.5 * self.shape**2) * math.sqrt(math.expm1(self.shape**2)))
        return float(self.scale / math.sqrt(12.0))

    @functools.cached_property
    def mean(self) -> float:
        """Mean, in closed form (the scipy distribution's ``mean()``)."""
        if self.dist == "halfnormal":
            return float(self.loc + self.scale * math.sqrt(2.0 / math.pi))
        if self.dist == "lognormal":
            return float(self.loc + self.scale * math.exp(0.5 * self.shape**2))
        return float(self.loc + (0.5 * self.scale if self.dist == "uniform" else 0.0))

    @functools.cached_property
    def centre(self) -> float:
        """Centre of the sampling coordinate (mean; 0 for half-normal and log-normal, sampled in log σ)."""
        return {"normal": self.loc, "halfnormal": 0.0, "lognormal": 0.0}.get(self.dist, self.loc + 0.5 * self.scale)

    def describe(self) -> str:
        d = lambda v: f"{units.from_internal(v, self.unit):g}"  # noqa: E731
        sym = units.SYMBOL[self.unit]
        if self.dist == "normal":
            return f"Normal({d(self.loc)}, {d(self.scale)} {sym})"
        if self.dist == "halfnormal":
            return f"HalfNormal({d(self.scale)} {sym})"
        if self.dist == "lognormal":
            return f"LogNormal(median {d(self.scale)} {sym}, log sd {self.shape:g})"
        return f"Uniform({d(self.loc)}, {d(self.loc + self.scale)} {sym})"


def make_prior(name: str, base: str, kind: str, overrides: dict[str, dict], *,
               stated: dict[str, float] | None = None) -> Prior:
    """The prior of parameter ``name`` (base name ``base``): campaign override, else the sd an instrument's section
    states for it (``stated`` {base: sd, internal units}: the R-test's, :meth:`~mtmcal_bayes.campaign.RTest.prior_sds`),
    else default."""
    unit = "arcsec" if kind == "angle" else "um"
    if base not in overrides and stated and base in stated:
        return Prior(name, "normal", 0.0, stated[base], unit, STATED_REASON)
    if base in overrides:
        spec = overrides[base]
        reason = "set in the campaign's [priors]"
        if spec["dist"] == "uniform":
            return Prior(name, "uniform", spec["low"], spec["high"] - spec["low"], unit, reason)
        return Prior(name, spec["dist"], spec.get("mean", 0.0), spec["sd"], unit, reason)
    dist, sd, reason = DEFAULTS.get(base, DEFAULTS[kind])
    return Prior(name, dist, 0.0, units.to_internal(sd, unit), unit, reason)


def learnt_prior(name: str, sigma_prior) -> Prior:
    """The prior of discrepancy scale ``name`` from a :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior` (which
    must name it): log-normal, its reason the source it was learnt from."""
    median, log_sd = sigma_prior.scales[name]
    return Prior(name, "lognormal", 0.0, units.to_internal(median, "um"), "um",
                 f"learnt elsewhere: {sigma_prior.source}", shape=log_sd)


class PriorSet:
    """Joint prior of independent parameters, vectorised over batches ``(n, q)``."""

    def __init__(self, priors: list[Prior]):
        self.priors = list(priors)
        self.names = [p.name for p in self.priors]
        self._groups = {}
        for dist in ("normal", "halfnormal", "uniform", "lognormal"):
            idx = np.array([i for i, p in enumerate(self.priors) if p.dist == dist], dtype=int)
            if len(idx):
                loc = np.array([self.priors[i].loc for i in idx])
                scale = np.array([self.priors[i].scale for i in idx])
                if dist == "lognormal":  # ln x ~ N(ln median, shape²): the location and width of ln x
                    shape = np.array([self.priors[i].shape for i in idx])
                    self._groups[dist] = (idx, loc, (np.log(scale), shape), self._log_norm("normal", shape))
                    continue
                self._groups[dist] = (idx, loc, scale, self._log_norm(dist, scale))
        self.centre = np.array([p.centre for p in self.priors])
        self.width = np.array([p.sd for p in self.priors])

    @staticmethod
    def _log_norm(dist: str, scale: np.ndarray) -> float:
        """Sum over a family of the log normalising constants of its densities."""
        if dist == "normal":
            return float(-np.sum(np.log(scale)) - len(scale) * _LOG_SQRT_2PI)
        if dist == "halfnormal":
            return float(len(scale) * math.log(2.0) - np.sum(np.log(scale)) - len(scale) * _LOG_SQRT_2PI)
        return float(-np.sum(np.log(scale)))

    def logpdf(self, theta: np.ndarray) -> np.ndarray:
        """Joint log-density ``(n,)`` of a batch ``(n, q)`` (internal units); −inf outside the support.

        Plain numpy: normal ``−½((x−μ)/s)² − log s − log√(2π)``; half-normal the same
        plus ``log 2`` on ``x ≥ loc``; uniform ``−log(width)`` on ``[low, high]``; log-normal
        ``−½((ln x − ln m)/s)² − log s − log√(2π) − ln x`` on ``x > 0`` (``m`` the median).
        """
        theta = np.atleast_2d(theta)
        out = np.zeros(theta.shape[0])
        for dist, (idx, loc, scale, log_norm) in self._groups.items():
            x = theta[:, idx]
            if dist == "uniform":
                inside = np.all((x >= loc) & (x <= loc + scale), axis=1)
                out += np.where(inside, log_norm, -np.inf)
                continue
            if dist == "lognormal":
                log_median, shape = scale
                positive = np.all(x > loc, axis=1)
                lx = np.log(np.where(x > loc, x - loc, 1.0))  # outside the support: −inf below, not a warning
                u = (lx - log_median) / shape
                out += np.where(positive, log_norm - 0.5 * np.einsum("ij,ij->i", u, u) - lx.sum(axis=1), -np.inf)
                continue
            u = (x - loc) / scale
            out += log_norm - 0.5 * np.einsum("ij,ij->i", u, u)
            if dist == "halfnormal":
                out[np.any(x < loc, axis=1)] = -np.inf
        return out

    def rvs(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """``n`` independent draws, shape ``(n, q)``."""
        return np.column_stack([p.draw(n, rng) for p in self.priors])
