"""Checks a posterior owes its reader: how far it is from the exact (or linearised) posterior, does the linear
model's first order hold (what the thesis' dx_BT = 0 would change is its plug-in's: ``plugins/thesis/assumption.py``)."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass


from .. import units
from ..inference.sampling import SamplingResult
from ..models import default_kinematic_model, first_order_gap
from ..machines.plugins import provided


def linear_model_check(result: SamplingResult) -> list[str]:
    """A warning when the linear model's first order does not hold at the deviations found.

    At the posterior mean, the kinematic model ``htm-thesis`` (whose first order is the
    linear model) is compared with the linear model; a difference above the instrument
    accuracy means the deviations are too large for the linear model (thesis
    magnitudes leave 0.06 µm, deviations of a degree millimetres).
    """
    post = result.posterior
    if post.model_name != "linear":
        return []
    theta = result.chains.reshape(-1, result.chains.shape[-1])[:, : post.p].mean(axis=0)
    gap = first_order_gap(post.campaign, theta, post.space, observations=post.ballbar_observations)
    accuracy = post.campaign.ballbar.accuracy
    if gap <= accuracy:
        return []
    kinematic = default_kinematic_model(post.campaign.machine)
    return [f"the linear model is first order and the deviations found are too large for it: at the posterior "
            f"mean the kinematic model {kinematic} predicts eccentricities up to {units.from_internal(gap, 'um'):.1f} "
            f"µm away from it (instrument accuracy {units.from_internal(accuracy, 'um'):g} µm); use the {kinematic} "
            "model"]


@dataclass(frozen=True)
class ReferenceCheck:
    """The sampled posterior against a reference: the exact σ-marginal posterior (``linear``, normal priors),
    else the linearised one, where the difference is model-form information, not sampler error.

    Per quantity the reference mean and sd (display units), ``mean_diff_sd`` = (sampled − reference mean) /
    reference sd and ``sd_diff_pct`` = sampled / reference sd − 1 in %; the largest absolute differences over
    the eight quantities of Table 4.5.
    """

    reference: str
    exact: bool
    max_mean_diff_sd: float
    max_sd_diff_pct: float
    reference_mean: dict[str, float]
    reference_sd: dict[str, float]
    mean_diff_sd: dict[str, float]
    sd_diff_pct: dict[str, float]
    #: how many quantities the largest differences are over (the thesis machine's eight of Table 4.5, a described
    #: machine's deviations); said in the sentence, not part of the JSON
    n_compared: int

    def to_json(self) -> dict:
        out = asdict(self)
        del out["n_compared"]
        return out

    def sentence(self) -> str:
        what = "the exact σ-marginal posterior" if self.exact else f"the {self.reference} (model-form information)"
        return (f"against {what}: means within {self.max_mean_diff_sd:.3f} sd and sds within "
                f"{self.max_sd_diff_pct:.1f} % for the {units.in_words(self.n_compared)} quantities")


#: an exact reference further than this many Monte-Carlo standard errors away is a warning
REFERENCE_MCSE = 4.0


def reference_check(result: SamplingResult, summary) -> ReferenceCheck | None:
    """Compare ``summary`` (from :func:`~mtmcal_bayes.inference.results.summarize`) with the approximation the
    sampler started from; None when the run has none or it gives no finite moments for the eight."""
    approx = result.approximation
    if approx is None:
        return None
    ref = {n: v for n, v in approx.moments(list(summary.index)).items()
           if all(map(math.isfinite, v)) and v[1] > 0}
    names = [n for n in summary.index if n in ref]
    own = provided(result.posterior.campaign.machine, "reported_quantities")  # a plug-in's (the thesis' eight)
    eight = [n for n in own if n in names] if own is not None else [n for n in names if n in result.posterior.space.names]
    if not eight:
        return None
    mean = {n: float((summary.loc[n, "mean"] - ref[n][0]) / ref[n][1]) for n in names}
    sd = {n: float(100.0 * (summary.loc[n, "sd"] / ref[n][1] - 1.0)) for n in names}
    return ReferenceCheck(approx.kind, approx.exact, max(abs(mean[n]) for n in eight), max(abs(sd[n]) for n in eight),
                          {n: ref[n][0] for n in names}, {n: ref[n][1] for n in names}, mean, sd, len(eight))


def reference_warnings(check: ReferenceCheck | None, summary) -> list[str]:
    """Quantities whose posterior is further from the exact posterior than Monte-Carlo error explains."""
    if check is None or not check.exact:
        return []
    out = []
    for n in check.mean_diff_sd:
        r = summary.loc[n]
        off_mean = abs(r["mean"] - check.reference_mean[n]) > REFERENCE_MCSE * r["mcse_mean"]
        off_sd = abs(r["sd"] - check.reference_sd[n]) > REFERENCE_MCSE * r["mcse_sd"]
        if off_mean or off_sd:
            out.append(f"{n}: the sampled posterior differs from the exact one by more than {REFERENCE_MCSE:g} "
                       f"Monte-Carlo standard errors (mean {check.mean_diff_sd[n]:+.3f} sd, sd "
                       f"{check.sd_diff_pct[n]:+.1f} %): do not trust this run")
    return out
