"""The deviations a program is compensated with, and posterior draws for its uncertainty."""

from __future__ import annotations

import numpy as np

from .... import units
from ....errors import InputError, MtmcalError
from ....inference.analytic import gaussian_posterior
from ....inference.log_posterior import LogPosterior
from ....io.netcdf import read_posterior
from ....compensation.options import N_DRAWS, SIGMA_MODEL_UM
from ..identification import identify
from ....parameters import DERIVED, DEVIATIONS



def ballbar_values(campaign) -> np.ndarray:
    """(13,) the deterministic ball-bar values (thesis Table 4.5 for the thesis campaign), internal units.

    As the thesis: dx_BT = 0 (Eq 4.2), so a derived quantity is carried by its first deviation
    (dx_CZ = dx_CZ − dx_BT); dz_BT and the squareness terms 0.
    """
    ident = identify(campaign).ballbar
    theta = np.zeros(len(DEVIATIONS))
    for name, v in ident.items():
        if v.value is None:
            raise MtmcalError(f"the ball-bar value of {name} cannot be computed: it {v.missing}")
        key = next(iter(DERIVED[name])) if name in DERIVED else name
        theta[list(DEVIATIONS).index(key)] = v.value
    return theta


def posterior_draws(campaign, source=None, *, n: int = N_DRAWS, seed: int = 0) -> tuple[np.ndarray, str]:
    """(n, 13) deviation draws, internal units, and where they come from.

    ``source``: a posterior NetCDF file (``sample -o``), a posterior from :func:`mtmcal_bayes.sample`
    or an ArviZ InferenceData; None: the closed-form posterior of the linear model.
    """
    rng = np.random.default_rng(seed)
    if source is not None:
        idata = getattr(source, "idata", source)  # a PosteriorResult carries its InferenceData
        if hasattr(idata, "posterior"):
            post, where = idata.posterior, "the given posterior"
        else:
            post, where = read_posterior(source), str(source)
        names = [d for d in DEVIATIONS if d in post]
        if not names:
            raise InputError(where, None, "holds no deviation draws (is it a posterior from mtmcal-bayes sample?)")
        cols = {d: np.asarray(post[d]).ravel() for d in names}
        total = len(next(iter(cols.values())))
        idx = np.linspace(0, total - 1, min(n, total)).astype(int)
        draws = np.zeros((len(idx), len(DEVIATIONS)))
        for d in names:
            draws[:, list(DEVIATIONS).index(d)] = units.to_internal(cols[d][idx], DEVIATIONS[d].unit)
        return draws, f"posterior draws from {where}"
    sigma = units.to_internal(SIGMA_MODEL_UM, "um")
    g = gaussian_posterior(LogPosterior(campaign, "linear", sigma_model=sigma), sigma, allow_non_normal=True)
    raw = g.draws(n, rng)
    draws = np.zeros((n, len(DEVIATIONS)))
    for i, name in enumerate(g.names):
        if name in DEVIATIONS:
            draws[:, list(DEVIATIONS).index(name)] = raw[:, i]
    return draws, f"closed-form posterior of the linear model (sigma_model {SIGMA_MODEL_UM:g} µm), {n} draws"
