"""The values a program is compensated with, on any machine, and the posterior draws they come from.

:func:`deviation_draws` reads a posterior's draws; :func:`classify_values` decides the values by the one rule of
"determined" (the campaign's Jacobian, nuisance terms included): the posterior mean of every deviation the model
estimates — under the posterior the value of least expected squared error — except one whose posterior is its prior
(undetermined, and no nuisance prior informs it: the separate prior-sensitivity diagnostic names none), left at zero;
:func:`value_warnings` names each value the data do not determine one by one and the nuisance priors it rests on.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import units
from ..errors import InputError
from ..inference.identifiability import DETERMINED
from ..inference.identifiability import IN_COMBINATION as IN_COMBINATION_VERDICT
from ..inference.log_posterior import LogPosterior
from ..io.netcdf import read_posterior, read_posterior_attrs
from ..machines.deviations import generated
from ..machines.selection import redundant
from .options import N_DRAWS, SIGMA_MODEL_UM

#: why a deviation is not compensated with a measured value, by its class
LEFT_AT_ZERO = "not determined by this campaign (its posterior is its prior): left at zero, its prior mean; its " \
               "prior spread is in the residual band"
THROUGH_PRIORS = "not determined by this campaign's data (its Jacobian, nuisance terms included), but its posterior " \
                 "rests on the nuisance prior{s} {names}: compensated with its posterior mean, as good as that " \
                 "set-up knowledge"
HELD_AT_ZERO = "not estimated by the machine's model ({why}): held at zero, not in the residual band"
IN_COMBINATION = "determined only in combination ({names}): compensated with its posterior mean, whose split " \
                 "within the combination is the prior's"


@dataclass
class Draws:
    """Deviation draws a plug-in gives as its machine's default posterior: ``draws`` ``{name: (n,)}`` internal
    units, the (linear) ``log_posterior`` they come from and ``label``, what the result says they are (with the
    number of draws)."""

    draws: dict[str, np.ndarray]
    log_posterior: LogPosterior
    label: str


def deviation_draws(campaign, posterior, *, n: int = N_DRAWS, label: str | None = None) -> tuple[dict[str, np.ndarray], object, str]:
    """``({name: (n,)} internal units, log posterior, where from)``: the deviation draws of ``posterior`` (a
    :class:`Draws`, a :class:`~mtmcal_bayes.posterior.sample.PosteriorResult`, an InferenceData or a NetCDF file of
    ``sample -o``), thinned evenly to at most ``n``, and the (linear) log posterior whose identifiability they are
    read with; ``label``: what the draws are, for where from (default: the posterior given)."""
    if isinstance(posterior, Draws):
        count = len(next(iter(posterior.draws.values())))
        return posterior.draws, posterior.log_posterior, f"{label or posterior.label}, {count} draws"
    lp = getattr(posterior, "log_posterior", None)
    idata = getattr(posterior, "idata", posterior)
    if hasattr(idata, "posterior"):
        post, where = idata.posterior, "the given posterior"
        data = lp.data if lp is not None else str(idata.posterior.attrs.get("data", "ballbar"))
    else:
        post, where = read_posterior(posterior), str(posterior)
        data = str(read_posterior_attrs(posterior).get("data", "ballbar"))
    if lp is None or lp.model_name != "linear":
        lp = LogPosterior(campaign, "linear", data=data)
    devs = [p for p in lp.space.parameters if p.group == "deviation"]
    if not any(p.name in post for p in devs):
        raise InputError(where, None, "holds no draws of this machine's deviations (is it a posterior of this "
                         "campaign from mtmcal-bayes sample?)")
    total = int(np.asarray(post[next(p.name for p in devs if p.name in post)]).size)
    idx = np.linspace(0, total - 1, min(n, total)).astype(int)
    draws = {p.name: units.to_internal(np.ravel(np.asarray(post[p.name]))[idx], p.unit) for p in devs if p.name in post}
    return draws, lp, f"{label}, {len(idx)} draws" if label else f"posterior draws from {where}"


def sigma_model_um(posterior) -> float:
    """σ_model (µm) of a posterior's prior-sensitivity diagnostic: the median of its draws where it has them, else
    :data:`SIGMA_MODEL_UM`."""
    idata = getattr(posterior, "idata", posterior)
    post = getattr(idata, "posterior", None)
    return float(np.median(post["sigma_model"])) if post is not None and "sigma_model" in post else SIGMA_MODEL_UM


def classify_values(campaign, draws: dict[str, np.ndarray], ident,
                    through: dict[str, tuple[str, ...]]) -> tuple[dict[str, float], list[dict]]:
    """The values compensated with ``{name: value}`` (internal units) and the deviations not compensated with a
    value the data determine, each ``{"name", "status", "why"}``: ``left at zero`` (the campaign's Jacobian leaves
    it undetermined, ``ident``, and no nuisance prior informs it, ``through`` of the prior-sensitivity diagnostic:
    its posterior is its prior, whose mean is zero), ``through nuisance priors`` (undetermined, its posterior mean
    set by set-up knowledge: compensated with it), ``in combination``, ``held at zero`` (not estimated)."""
    desc = campaign.machine.description
    combos: dict[str, list[str]] = {}
    for c in ident.combinations:
        for name in c.weights:
            combos.setdefault(name, []).append(c.name)
    values, notes = {}, []
    reasons = redundant(desc)
    for d in generated(desc):
        priors = through.get(d.name, ())
        if d.name not in draws:
            notes.append({"name": d.name, "status": "held at zero",
                          "why": HELD_AT_ZERO.format(why=reasons.get(d.name, "not selected in the description"))})
        elif d.name in ident.undetermined and not priors:
            notes.append({"name": d.name, "status": "left at zero", "why": LEFT_AT_ZERO})
        else:
            values[d.name] = float(np.mean(draws[d.name]))
            if d.name in ident.undetermined:
                notes.append({"name": d.name, "status": "through nuisance priors",
                              "why": THROUGH_PRIORS.format(s="s" if len(priors) > 1 else "",
                                                           names=" and ".join(priors))})
            elif d.name not in ident.determined:
                notes.append({"name": d.name, "status": "in combination",
                              "why": IN_COMBINATION.format(names="; ".join(combos.get(d.name, [])))})
    return values, notes


def value_warnings(ident, through: dict[str, tuple[str, ...]], values: dict[str, float],
                   unit: dict[str, str]) -> list[str]:
    """One warning for each deviation compensated with a value that rests on more than the data: one the data do not
    determine one by one (the campaign's Jacobian, ``ident``), or one whose value rests on nuisance priors
    (``through``, the prior-sensitivity diagnostic), or both, said in one line; each among the quantities the
    diagnostic reports."""
    out = []
    for name, value in values.items():
        if name not in through or value == 0.0:
            continue
        verdict, combos = ident.of(name)
        why = []
        if verdict == IN_COMBINATION_VERDICT:
            why.append(f"which the data determine only in combination ({'; '.join(combos)}): its own value follows "
                       "the priors")
        elif verdict != DETERMINED:
            why.append("which the data do not identify (the campaign's Jacobian leaves it undetermined; its value "
                       "follows the priors)")
        if through[name]:
            why.append(f"whose value rests on the nuisance prior{'s' if len(through[name]) > 1 else ''} "
                       f"{' and '.join(through[name])}: the correction is as good as that set-up knowledge "
                       "(docs/metrology.md)")
        if why:
            shown = f"{name} = {units.from_internal(value, unit[name]):.3g} {units.SYMBOL[unit[name]]}"
            out.append(f"compensating with {shown}, " + "; and ".join(why))
    return out
