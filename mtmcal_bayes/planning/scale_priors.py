"""The priors of the discrepancy scales a plan or design weighs: assumed, or learnt elsewhere by a fleet of the
machine type (:class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior`, ``--sigma-model-prior``), and what σ_model's
contraction is measured against under a learnt prior.

Under a learnt prior the contraction is ``1 − var_post / max(var_assumed, var_learnt)`` (docs/design.md): a learnt
prior narrower than the assumed one counts as knowledge of σ_model — the goal is then the absolute precision it is
without one, and a learnt prior narrower than the goal meets it before any run — while one wider is narrowed by the
data as the assumed one would be.  Without a learnt prior the reference is the prior itself, as it always was.
"""

from __future__ import annotations

import math

from .. import units
from ..inference.priors import Prior, learnt_prior, make_prior
from ..parameters import SCALE_LABEL


def scale_prior(campaign, name: str = "sigma_model", learnt=None) -> Prior:
    """The prior of a discrepancy scale (``sigma_model``, ``sigma_model_probe``): the one ``learnt`` elsewhere (a
    :class:`~mtmcal_bayes.sigma_prior.SigmaModelPrior`) where it names the scale, else the campaign's ``[priors]``,
    else the default (the assumed prior)."""
    if learnt is not None and name in learnt.scales:
        return learnt_prior(name, learnt)
    return make_prior(name, name, "length", campaign.priors)


def default_sigma_model(campaign, name: str = "sigma_model", learnt=None) -> float:
    """Root mean square of a discrepancy scale's prior (``sigma_model``, ``sigma_model_probe``; :func:`scale_prior`),
    mm: the fixed value the closed form uses."""
    prior = scale_prior(campaign, name, learnt)
    return float(math.sqrt(prior.sd**2 + prior.mean**2))


def reference_prior(campaign, learnt) -> tuple[Prior, str] | None:
    """Under a learnt prior, the prior σ_model's contraction is measured against and which it is: the wider (in
    variance) of the assumed one (the campaign's ``[priors]`` or the default), ``"assumed"``, and the learnt one,
    ``"learnt"`` (a tie: the assumed); None without a learnt prior."""
    if learnt is None:
        return None
    assumed, own = scale_prior(campaign, "sigma_model"), scale_prior(campaign, "sigma_model", learnt)
    return (own, "learnt") if float(own.frozen().var()) > float(assumed.frozen().var()) else (assumed, "assumed")


def contraction_reference(campaign, learnt) -> float | None:
    """The variance σ_model's contraction is measured against, mm²: None (its prior's) without a learnt prior; under
    one, the larger of the assumed and the learnt prior's variance (:func:`reference_prior`)."""
    ref = reference_prior(campaign, learnt)
    return None if ref is None else float(ref[0].frozen().var())


def learnt_summary(campaign, learnt) -> dict:
    """What a plan's or design's JSON says of a σ_model prior learnt elsewhere (empty without one): ``prior``
    (``LogNormal(median 1 µm, log sd 0.1)``), ``prior_source`` (``{"source": "learnt", "from": <source>}``) and
    ``contraction_reference``: the prior the contraction is measured against (``prior``, ``which``: ``"assumed"``
    or ``"learnt"``, its ``sd_um``)."""
    if learnt is None:
        return {}
    ref, which = reference_prior(campaign, learnt)
    return {"prior": scale_prior(campaign, "sigma_model", learnt).describe(),
            "prior_source": {"source": "learnt", "from": learnt.source},
            "contraction_reference": {"prior": ref.describe(), "which": which,
                                      "sd_um": units.from_internal(math.sqrt(ref.frozen().var()), "um")}}


def learnt_notes(campaign, learnt, uses: str) -> list[str]:
    """The notes of a plan or design made under a σ_model prior learnt elsewhere (none without one): each learnt
    prior and its source, what uses it (``uses``), and what σ_model's contraction is measured against."""
    if learnt is None:
        return []
    ref = learnt_summary(campaign, learnt)["contraction_reference"]
    return [f"{SCALE_LABEL[n]} prior: learnt elsewhere, {scale_prior(campaign, n, learnt).describe()}, from "
            f"{learnt.source} ({uses})" for n in SCALE_LABEL if n in learnt.scales] + [
        "σ_model's contraction is measured against the wider of the assumed and the learnt prior, here the "
        f"{ref['which']} {ref['prior']} (sd {ref['sd_um']:.3g} µm): 1 − var_post/var_wider, so a learnt prior "
        "narrower than the assumption counts as knowledge of σ_model (narrower than the goal, it meets it before any "
        "run), while a wider one must be narrowed by the data as the assumed one would (docs/design.md)"]


__all__ = ["scale_prior", "default_sigma_model", "reference_prior", "contraction_reference", "learnt_summary",
           "learnt_notes"]
