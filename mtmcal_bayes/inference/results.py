"""Posterior results: ArviZ InferenceData, the per-quantity summary, diagnostics warnings (SPEC §5).

Values in the InferenceData and the tables are in display units (″ and µm).
Derived quantities (``dx_CZ_minus_dx_BT``) are added to the draws from their
definition in :data:`~mtmcal_bayes.parameters.DERIVED`.
"""

from __future__ import annotations

import numpy as np
import pandas as pd

from .. import units
from ..arviz_import import az
from ..iso import iso_symbol
from ..observations import JointObservations, ProbeObservations, RTestObservations
from ..parameters import DERIVED, NUISANCE_MEANING, combine, iso_kind, quantity_unit, weights
from .analytic import NOT_IDENTIFIED_GROWTH, WIDEN, prior_sensitivity, reported
from .budget import linearisation_point, variance_budget
from .gum import gum_table
from .identifiability import DETERMINED, IN_COMBINATION, UNDETERMINED, Identifiability, campaign_identifiability

HDI_PROB = 0.95
RHAT_MAX = 1.01
ESS_MIN = 400
#: posterior draws kept per chain in the InferenceData (the file stays a few MB; the ESS is kept)
MAX_DRAWS_PER_CHAIN = 4000


def display_draws(names: list[str], draws: np.ndarray) -> dict[str, np.ndarray]:
    """Dict of display-unit draws (…,) per name of ``draws`` (…, len(names)), plus the derived quantities."""
    out = {n: units.from_internal(draws[..., i], quantity_unit(n)) for i, n in enumerate(names)}
    for name, w in DERIVED.items():
        if all(k in out for k in w):  # a described machine has no dx_CZ, dx_BT
            out[name] = combine(name, out)
    return out


def observation_parts(observations) -> list[tuple[str, object, slice]]:
    """``(variable name, observations, slice)`` of each kind of measurement in ``observations``:
    ``"eccentricity"`` for the ball bar's, ``"probe_reading"`` for the probe's, ``"rtest_reading"`` for the R-test's
    (each its own variable: with the probe's beside them, one name would hide the other's)."""
    parts = observations.slices() if isinstance(observations, JointObservations) else [
        (observations, slice(0, len(observations)))]
    return [("rtest_reading" if isinstance(o, RTestObservations) else "probe_reading"
             if isinstance(o, ProbeObservations) else "eccentricity", o, sl) for o, sl in parts]


def to_inference_data(result, n_prior: int = 4000, n_predictive: int = 1000,
                      seed: int | None = None, *, posterior_only: bool = False) -> az.InferenceData:
    """InferenceData of a :class:`~.sampling.SamplingResult`: posterior, prior, posterior predictive, observed data
    and sample stats (``posterior_only``: the posterior and sample stats alone, for a posterior shown beside
    another, whose prior, predictions and pointwise log-likelihood nothing reads).

    Posterior draws: chain = ensemble, draw = the walkers' sequences one after the
    other, so that ArviZ's autocorrelation-based ESS sees each walker's own
    autocorrelation (interleaving walkers step by step would hide it).
    """
    post = result.posterior
    # thin by a quarter of the deviations' median τ (the ESS is kept), and to at most MAX_DRAWS_PER_CHAIN
    dev = [i for i, p in enumerate(post.space.parameters) if p.group == "deviation"]
    steps, walkers = result.chains.shape[1:3]
    thin = max(1, int(np.median(result.tau[:, dev]) // 4), -(-steps * walkers // MAX_DRAWS_PER_CHAIN))
    chains, logp = result.chains[:, ::thin], result.log_prob[:, ::thin]
    K, S, W, q = chains.shape
    flat = np.swapaxes(chains, 1, 2).reshape(K, W * S, q)
    lp = np.swapaxes(logp, 1, 2).reshape(K, W * S)
    posterior = display_draws(post.names, flat)
    if posterior_only:
        return _with_attrs(az.from_dict(posterior=posterior, sample_stats={"lp": lp}), result, thin)
    rng = np.random.default_rng(seed)
    prior = display_draws(post.names, post.priors.rvs(n_prior, rng)[None])

    # posterior predictive of the repeat means from an even subset of draws per ensemble
    idx = np.linspace(0, S * W - 1, min(n_predictive, S * W)).astype(int)
    sub = flat[:, idx, :].reshape(-1, q)
    pred = post.forward.predict(sub[:, : post.p])
    rep = units.from_internal(post.likelihood.replicate(pred, post.sigma(sub), rng).reshape(K, len(idx), -1), "um")
    # pointwise log-likelihood of every kept draw (PSIS-LOO, posterior.loo): Normal density of the observed
    # mean in µm, variance base_var + sigma_model² of that draw — one forward-model call on all draws
    every = flat.reshape(-1, q)
    mu = units.from_internal(post.forward.predict(every[:, : post.p]), "um")
    sd = units.from_internal(np.sqrt(post.likelihood.variance(post.sigma(every))), "um")
    z = (units.from_internal(post.likelihood.y, "um") - mu) / sd
    loglik = (-0.5 * (z * z + np.log(2 * np.pi)) - np.log(sd)).reshape(K, W * S, -1)
    observed, predictive, log_likelihood, coords, dims = {}, {}, {}, {}, {}
    for var, obs, sl in observation_parts(post.forward.observations):
        coords[f"{var}_observation"] = obs.labels
        dims[var] = [f"{var}_observation"]
        predictive[var] = rep[..., sl]
        log_likelihood[var] = loglik[..., sl]
        observed[var] = units.from_internal(obs.mean, "um")
    if "eccentricity" in dims:  # the ball bar's keep their historical name
        coords["observation"] = coords.pop("eccentricity_observation")
        dims["eccentricity"] = ["observation"]
    idata = az.from_dict(
        posterior=posterior,
        prior=prior,
        posterior_predictive=predictive,
        log_likelihood=log_likelihood,
        observed_data=observed,
        sample_stats={"lp": lp},
        coords=coords,
        dims=dims,
    )
    idata = _with_attrs(idata, result, thin)
    idata.observed_data.attrs["unit"] = "um (mean of the repeats; probe readings minus their nominal)"
    idata.log_likelihood.attrs["unit"] = ("log density of the observed mean in um (Normal, variance base + the "
                                          "instrument's discrepancy scale²)")
    return idata


def _with_attrs(idata, result, thin: int):
    """``idata`` with the run's facts as attributes of its posterior group."""
    post = result.posterior
    K, _, W, _ = result.chains.shape
    idata.posterior.attrs.update({
        "model": post.model_name, "campaign": post.campaign.source, "fix_dx_BT": int(post.fix_dx_BT),
        "data": post.data,
        "n_ensembles": K, "n_walkers": W, "n_steps": result.n_steps, "burn_in": result.burn, "thin": thin,
        "tau_max_steps": float(np.nanmax(result.tau)), "converged": int(result.converged),
        "sampler": result.settings.sampler, "target_ess": float(result.settings.target_ess),
        "independence_acceptance": float(result.independence_acceptance),
        "seed": -1 if result.settings.seed is None else int(result.settings.seed),
        "units": "arc seconds for angles, micrometres for lengths",
    })
    if post.fixed_sigma is not None:  # the discrepancy scales were fixed, not sampled (compensate reads it back)
        idata.posterior.attrs["sigma_model_fixed_um"] = float(units.from_internal(post.fixed_sigma, "um"))
    return idata


def prior_sd(result_or_post, names) -> dict[str, float]:
    """Prior sd (display units) of each name, including the derived quantities (independent priors)."""
    post = getattr(result_or_post, "posterior", result_or_post)
    sd = {p.name: units.from_internal(p.sd, quantity_unit(p.name)) for p in post.priors.priors}
    for name in DERIVED:
        sd[name] = float(np.hypot.reduce([w * sd[k] for k, w in weights(name, sd).items()]))
    return {n: sd[n] for n in names if n in sd}


def summarize(idata, post, names=None, *, statement: bool = True, diagnostics: bool = True,
              identifiability: Identifiability | None = None) -> pd.DataFrame:
    """One row per quantity: its ISO 230-7 symbol, mean, sd, median, 95 % HDI, R-hat, bulk/tail ESS, unit,
    prior sd, what the data determine of it, the prior-sensitivity diagnostic, the Monte-Carlo standard errors of
    mean and sd, and the GUM statement (:data:`~mtmcal_bayes.inference.gum.GUM_COLUMNS`).

    Whether the data determine a quantity is the campaign's Jacobian's statement (``identifiability``, default
    :func:`~.identifiability.campaign_identifiability` of ``post``; SPEC §20), on every machine:
    ``identification`` is ``"data"`` (determined one by one), ``"combination"`` (only within the estimable
    combinations named in ``combination``, ``"; "``-separated) or ``"not identified"``; ``identified`` is True for
    ``"data"`` only, and both are None where no statement applies (the discrepancy scales).

    The prior-sensitivity check (:func:`~mtmcal_bayes.inference.analytic.prior_sensitivity`) is a separate
    diagnostic that never decides ``identified``: ``sd_ratio`` is posterior sd / prior sd; ``prior_growth`` how much
    the posterior sd grows when the deviation priors widen tenfold, ``nuisance_growth`` when the nuisance priors
    do; ``identified_through`` the nuisance priors a quantity's interval rests on (comma-separated base names,
    empty otherwise) and ``prior_sensitivity`` its sentence (``"rests on the nuisance prior dRB"``; empty when
    none).

    ``statement=False`` leaves out the GUM statement and the uncertainty budget (intervals and identifiability
    only: what a posterior shown beside another needs).  ``diagnostics=False``, for independent draws of the exact
    posterior: no chain diagnostics (R-hat, ESS and Monte-Carlo standard errors are NaN: they describe a Markov
    chain, and these draws are not one).
    """
    names = list(names or (list(reported(post)) + list(post.scales)))
    names = [n for n in names if n in idata.posterior]
    s = az.summary(idata, var_names=names, hdi_prob=HDI_PROB, round_to="none",
                   kind="all" if diagnostics else "stats")
    if not diagnostics:
        s = s.assign(**{c: np.nan for c in ("r_hat", "ess_bulk", "ess_tail", "mcse_mean", "mcse_sd")})
    s = s.rename(columns={"hdi_2.5%": "hdi_low", "hdi_97.5%": "hdi_high"})
    s["median"] = [float(idata.posterior[n].median()) for n in s.index]
    s["unit"] = [quantity_unit(n) for n in s.index]
    s["iso"] = [iso_symbol(n) or (n if iso_kind(n) else None) for n in s.index]  # a described machine's: its name
    psd = prior_sd(post, s.index)
    s["prior_sd"] = [psd.get(n, np.nan) for n in s.index]
    s["sd_ratio"] = s["sd"] / s["prior_sd"]
    ident = identifiability if identifiability is not None else campaign_identifiability(post)
    verdicts = [ident.of(n) for n in s.index]
    s["identification"] = pd.Series([v for v, _ in verdicts], index=s.index, dtype=object)
    s["identified"] = pd.Series([None if v is None else v == DETERMINED for v, _ in verdicts], index=s.index,
                                dtype=object)
    s["combination"] = pd.Series(["; ".join(c) if c else None for _, c in verdicts], index=s.index, dtype=object)
    sens = prior_sensitivity(post, scale_medians(idata, post))
    s["prior_growth"] = [sens.deviation_growth.get(n, np.nan) for n in s.index]
    s["nuisance_growth"] = [sens.nuisance_growth.get(n, np.nan) for n in s.index]
    s["identified_through"] = [", ".join(sens.through[n]) if n in sens.through else None for n in s.index]
    s["prior_sensitivity"] = [rests_on(t) for t in s["identified_through"]]
    s = s[["iso", "mean", "sd", "median", "hdi_low", "hdi_high", "r_hat", "ess_bulk", "ess_tail", "unit",
           "prior_sd", "sd_ratio", "prior_growth", "nuisance_growth", "identified", "identification", "combination",
           "identified_through", "prior_sensitivity", "mcse_mean", "mcse_sd"]]
    if not statement:
        return s
    return pd.concat([s, gum_table(idata, s), budget_columns(idata, post).reindex(s.index)], axis=1)


def rests_on(through: str | None) -> str | None:
    """The prior-sensitivity sentence of a quantity whose interval rests on the nuisance priors ``through``
    (comma-separated base names): ``"rests on the nuisance prior dRB"``, ``"… priors dRB and zT"``; ``""`` when it
    rests on none, None where the check does not apply."""
    if not isinstance(through, str):
        return None
    bases = [b for b in through.split(", ") if b]
    if not bases:
        return ""
    listed = bases[0] if len(bases) == 1 else ", ".join(bases[:-1]) + " and " + bases[-1]
    return f"rests on the nuisance prior{'s' if len(bases) > 1 else ''} {listed}"


def scale_draws(idata, post) -> np.ndarray | None:
    """Posterior draws ``(n, s)`` of the discrepancy scales, mm (None when they are fixed)."""
    if post.fixed_sigma is not None or not all(n in idata.posterior for n in post.scales):
        return None
    return np.column_stack([units.to_internal(np.asarray(idata.posterior[n], float).ravel(), "um")
                            for n in post.scales])


def scale_medians(idata, post) -> np.ndarray:
    """The discrepancy scales ``(s,)`` at which closed-form checks are made, mm: their fixed value, or each
    scale's posterior median."""
    draws = scale_draws(idata, post)
    if draws is None:
        return np.full(len(post.scales), float(post.fixed_sigma or 0.0))
    return np.median(draws, axis=0)


#: the words of the ``identification`` column (:meth:`~.identifiability.Identifiability.of`)
IDENTIFIED_BY_DATA, IN_COMBINATION, NOT_IDENTIFIED = DETERMINED, IN_COMBINATION, UNDETERMINED


def budget_columns(idata, post) -> pd.DataFrame:
    """``budget:<source>`` columns: each reported quantity's share of posterior variance by source
    (:func:`~mtmcal_bayes.inference.budget.variance_budget`), averaged over the posterior draws of the
    discrepancy scales; kinematic models linearised at the posterior mean."""
    return variance_budget(post, scale_draws(idata, post), theta0=linearisation_point(idata, post)).add_prefix("budget:")


def diagnostics_warnings(summary: pd.DataFrame) -> list[str]:
    """Loud warnings for R-hat > 1.01 or bulk ESS < 400 (SPEC §5)."""
    out = []
    for name, row in summary.iterrows():
        if not row["r_hat"] <= RHAT_MAX:
            out.append(f"{name}: R-hat {row['r_hat']:.3f} > {RHAT_MAX} — the ensembles disagree; do not trust it")
        if not row["ess_bulk"] >= ESS_MIN:
            out.append(f"{name}: bulk ESS {row['ess_bulk']:.0f} < {ESS_MIN} — too few effective draws")
    return out


def not_identified(summary: pd.DataFrame) -> list[str]:
    """Sentences for the quantities the data (the campaign's Jacobian) do not determine one by one: not at all, or
    only within the combinations named."""
    out = []
    for n, r in summary.iterrows():
        if r["identification"] == NOT_IDENTIFIED:
            out.append(f"{n}: not identified by the data (the campaign's Jacobian, nuisance terms included, leaves it "
                       f"undetermined) — its width is set by priors (its own, or the nuisance priors it is confounded with); "
                       f"posterior sd {r['sd']:.3g} "
                       f"{units.SYMBOL[r['unit']]} = {r['sd_ratio']:.2f} × prior sd")
        elif r["identification"] == IN_COMBINATION:
            out.append(f"{n}: determined only in combination: {r['combination']} — not one by one; its own width "
                       f"follows the priors (posterior sd {r['sd']:.3g} {units.SYMBOL[r['unit']]} = "
                       f"{r['sd_ratio']:.2f} × prior sd)")
    return out


def prior_sensitivity_notes(summary: pd.DataFrame) -> list[str]:
    """The prior-sensitivity diagnostic's sentences, which never decide ``identified``: each quantity whose interval
    rests on nuisance priors (naming them), and each the data determine whose width still follows the deviation
    priors (a weakly determined direction)."""
    out = []
    for n, r in summary.iterrows():
        if isinstance(r["identified_through"], str) and r["identified_through"]:
            out.append(identified_through_sentence(n, r["identified_through"].split(", "), r["nuisance_growth"]))
        if r["identification"] == IDENTIFIED_BY_DATA and r["prior_growth"] > NOT_IDENTIFIED_GROWTH:
            out.append(f"{n}: determined by the data, but weakly — widening the deviation priors {WIDEN:g}× widens it "
                       f"{r['prior_growth']:.1f}×")
    return out


def identified_through_sentence(name: str, bases: list[str], growth: float) -> str:
    """"dz_BT: rests on the nuisance priors dRB (…) and zT (…)": the nuisance priors its interval rests on."""
    what = [f"{b} ({NUISANCE_MEANING[b]})" for b in bases]
    listed = what[0] if len(what) == 1 else ", ".join(what[:-1]) + " and " + what[-1]
    return (f"{name}: rests on the nuisance prior{'s' if len(what) > 1 else ''} {listed} — widening the "
            f"nuisance priors {WIDEN:g}× widens it {growth:.1f}×; its interval states that set-up knowledge as much "
            "as the machine")


def combination_summaries(ident: Identifiability, idata) -> list[dict]:
    """Each combination with its posterior from the draws of ``idata``: ``{"name", "weights", "mean", "sd",
    "hdi_low", "hdi_high", "unit"}`` (display units; weights per display unit)."""
    out = []
    for c in ident.combinations:
        draws = sum(w * np.asarray(idata.posterior[n]) for n, w in c.weights.items())
        flat = np.ravel(draws)
        low, high = az.hdi(flat, hdi_prob=HDI_PROB)
        out.append({"name": c.name, "weights": dict(c.weights), "mean": float(flat.mean()),
                    "sd": float(flat.std(ddof=1)), "hdi_low": float(low), "hdi_high": float(high), "unit": c.unit})
    return out
