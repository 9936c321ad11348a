"""The deviations a program is compensated with, and posterior draws for its uncertainty."""

from __future__ import annotations

import warnings

import numpy as np

from .. import units
from ..errors import InputError, MtmcalError
from ..identify import identify
from ..parameters import DEVIATIONS

N_DRAWS = 1000
SIGMA_MODEL_UM = 2.0


def ballbar_values(campaign) -> np.ndarray:
    """(13,) the deterministic ball-bar values (thesis Table 4.5 for the thesis campaign), internal units.

    As the thesis: dx_BT = 0 (Eq 4.2), dx_CZ = dx_CZ − dx_BT, dz_BT and the squareness terms 0.
    """
    ident = identify(campaign).ballbar
    theta = np.zeros(len(DEVIATIONS))
    for name, v in ident.items():
        if v.value is None:
            raise MtmcalError(f"the ball-bar value of {name} cannot be computed: it {v.missing}")
        key = "dx_CZ" if name == "dx_CZ_minus_dx_BT" else name
        theta[list(DEVIATIONS).index(key)] = v.value
    return theta


def posterior_draws(campaign, path=None, n: int = N_DRAWS, seed: int = 0) -> tuple[np.ndarray, str]:
    """(n, 13) deviation draws, internal units: from a posterior NetCDF, else the closed-form posterior."""
    rng = np.random.default_rng(seed)
    if path is not None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", FutureWarning)
            import arviz as az
        try:
            idata = az.from_netcdf(path)
            post = idata.posterior
        except Exception as exc:  # noqa: BLE001 - any unreadable file is one line for the user
            raise InputError(str(path), None, f"cannot read as an ArviZ posterior NetCDF: {exc}") from None
        names = [d for d in DEVIATIONS if d in post]
        if not names:
            raise InputError(str(path), None, "holds no deviation draws (is it a posterior from mtmcal-bayes sample?)")
        cols = {d: np.asarray(post[d]).ravel() for d in names}
        total = len(next(iter(cols.values())))
        idx = np.linspace(0, total - 1, min(n, total)).astype(int)
        draws = np.zeros((len(idx), len(DEVIATIONS)))
        for d in names:
            draws[:, list(DEVIATIONS).index(d)] = units.to_internal(cols[d][idx], DEVIATIONS[d].unit)
        return draws, f"posterior draws from {path}"
    from ..inference.analytic import gaussian_posterior
    from ..inference.posterior import Posterior

    sigma = units.to_internal(SIGMA_MODEL_UM, "um")
    g = gaussian_posterior(Posterior(campaign, "linear", sigma_model=sigma), sigma, allow_non_normal=True)
    raw = g.draws(n, rng)
    draws = np.zeros((n, len(DEVIATIONS)))
    for i, name in enumerate(g.names):
        if name in DEVIATIONS:
            draws[:, list(DEVIATIONS).index(name)] = raw[:, i]
    return draws, f"closed-form posterior of the linear model (sigma_model {SIGMA_MODEL_UM:g} µm), {n} draws"
