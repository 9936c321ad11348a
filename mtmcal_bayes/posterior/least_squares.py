"""The deterministic identification of every machine: linearised least squares (SPEC §19, §20).

What a calibration engineer would compute on any machine: the least-squares solution of the forward model's first
order at the home pose, the nuisance terms held to their set-up knowledge (their priors act as pseudo-observations),
the deviations free (no prior), at a fixed σ_model.  Only what the campaign determines is stated — each deviation
determined one by one, each identifiable combination
(:func:`~mtmcal_bayes.inference.identifiability.campaign_identifiability`) and each derived quantity whose weights
the data determine (the thesis' dx_CZ − dx_BT), all of them estimable functions, whose estimate and covariance do not
depend on the generalised inverse chosen.

``identify`` gives it on every machine; a machine whose plug-in has a deterministic method of its own (the thesis':
Eqs 4.10–4.18 and 5.1–5.19 beside the published values) gets that beside it (:class:`Identification`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .. import units
from ..inference.analytic import linearisation
from ..inference.identifiability import Identifiability
from ..parameters import DERIVED
from ..parameters import weights as quantity_weights


@dataclass
class LeastSquares:
    """Estimates of the determined deviations, combinations and derived quantities: ``table`` with columns
    ``quantity, estimate, u, unit`` (display units), at ``sigma_model_um``."""

    table: pd.DataFrame
    sigma_model_um: float

    def values(self) -> dict[str, float]:
        """The estimates by quantity (display units): the values :func:`~.comparison.comparison` sets beside a
        posterior."""
        return dict(zip(self.table["quantity"], self.table["estimate"]))

    def to_json(self) -> dict:
        return {"sigma_model_um": self.sigma_model_um,
                "estimates": {r["quantity"]: {"estimate": r["estimate"], "u": r["u"], "unit": r["unit"]}
                              for _, r in self.table.iterrows()}}


def estimated_quantities(ident: Identifiability, names: list[str]) -> list[tuple[str, dict[str, float]]]:
    """``(name, weights)`` of what the least squares states (``names``: the parameter space's, deviations first):
    each deviation determined one by one, each combination, then each derived quantity
    (:data:`~mtmcal_bayes.parameters.DERIVED`) of deviations of the space whose weights the data determine and
    that is not already one of them."""
    out = [(n, {n: 1.0}) for n in ident.determined] + [(k.name, dict(k.weights)) for k in ident.combinations]
    classified = set(ident.deviations)
    for name in DERIVED:
        w = quantity_weights(name, names)
        if w and set(w) <= classified and name not in names and ident.estimable(w):
            out.append((name, w))
    return out


def least_squares(post, ident: Identifiability, sigma_model: float) -> LeastSquares:
    """The least-squares identification of ``post``'s campaign and data at ``sigma_model`` (mm, every scale).

    ``A θ + c`` the forward model's first order (:func:`~mtmcal_bayes.inference.analytic.linearisation`, (m, p)),
    ``V`` (m,) the variance of each observed mean at ``sigma_model``: the generalised least-squares normal equations
    ``(AᵀV⁻¹A + P) θ = AᵀV⁻¹(y − c) + P θ₀`` with ``P`` the nuisance priors' precisions (zero on the deviations),
    solved by the pseudo-inverse; only estimable quantities (:func:`estimated_quantities`) are read from it."""
    A, c = linearisation(post)
    V = post.likelihood.variance_at(sigma_model)
    names = post.space.names
    deviation = np.array([p.group == "deviation" for p in post.space.parameters])
    priors = post.priors.priors[:post.p]
    prior_prec = np.where(deviation, 0.0, 1.0 / np.array([q.sd for q in priors]) ** 2)
    centre = np.where(deviation, 0.0, np.array([q.centre for q in priors]))
    scale = post.space.display_scale()  # solved in display units (µm, ″): one footing for every column
    Ad = A * scale
    prec = Ad.T @ (Ad / V[:, None]) + np.diag(prior_prec * scale**2)
    rhs = Ad.T @ ((post.likelihood.y - c) / V) + prior_prec * scale * centre
    cov = np.linalg.pinv(prec, hermitian=True)
    est = cov @ rhs
    rows = []
    for name, weights in estimated_quantities(ident, names):
        w = np.zeros(len(names))
        for n, v in weights.items():
            w[names.index(n)] = v
        unit = next(p.unit for p in post.space.parameters if p.name == next(iter(weights)))
        rows.append({"quantity": name, "estimate": float(w @ est), "u": float(np.sqrt(w @ cov @ w)), "unit": unit})
    return LeastSquares(pd.DataFrame(rows, columns=["quantity", "estimate", "u", "unit"]),
                        float(units.from_internal(sigma_model, "um")))


@dataclass
class LeastSquaresIdentification:
    """The least-squares identification of a campaign: what it determines and the estimates, at σ_model = 0 (the
    measurements' own scatter and the instruments' accuracy: the deterministic method's view)."""

    campaign: object
    data: str
    ident: Identifiability
    estimates: LeastSquares

    def to_json(self) -> dict:
        return {"campaign": self.campaign.source, "machine": self.campaign.machine.description.configuration,
                "data": self.data, "identifiability": self.ident.as_dict(), **self.estimates.to_json()}

    def to_text(self) -> str:
        head = (f"Least-squares identification of {self.campaign.source} "
                f"({self.campaign.machine.description.configuration}, {self.data} data; the first order of the "
                "machine's kinematic model, the nuisance terms within their set-up knowledge, "
                f"σ_model = {self.estimates.sigma_model_um:g} µm)")
        lines = [head]
        for _, r in self.estimates.table.iterrows():
            lines.append(f"  {r['quantity']:34s} {r['estimate']:10.3f} ± {r['u']:.3f} {units.SYMBOL[r['unit']]}")
        if self.ident.undetermined:
            lines.append("  not determined by this campaign: " + ", ".join(self.ident.undetermined))
        return "\n".join(lines)


def identify_least_squares(campaign, data: str) -> LeastSquaresIdentification:
    """The least-squares identification of ``campaign`` from its ``data`` (``"ballbar"``, ``"probe"``, ``"both"``),
    the ``linear`` model (the first order of the machine's kinematics) at σ_model = 0."""
    from ..inference.identifiability import campaign_identifiability
    from ..inference.log_posterior import LogPosterior

    post = LogPosterior(campaign, "linear", data=data, sigma_model=0.0)
    ident = campaign_identifiability(post)
    return LeastSquaresIdentification(campaign, data, ident, least_squares(post, ident, 0.0))


@dataclass
class Identification:
    """What ``identify`` gives on every machine: the least squares (``least_squares``) and, where the machine's
    plug-in has a deterministic method of its own, its result (``own``: the thesis', an
    :class:`~mtmcal_bayes.plugins.thesis.identification.IdentificationResult`, with ``to_json``, ``to_text`` and
    ``table``)."""

    least_squares: LeastSquaresIdentification
    own: object | None = None

    def to_json(self) -> dict:
        """The plug-in's keys as its own result has them, then those of the least squares it lacks (``campaign`` is
        in both, with one value): one document whatever the machine."""
        own = self.own.to_json() if self.own is not None else {}
        return {**own, **{k: v for k, v in self.least_squares.to_json().items() if k not in own}}

    def to_text(self) -> str:
        """The plug-in's text as its own result prints it, then the least squares."""
        parts = [self.own.to_text()] if self.own is not None else []
        return "\n\n".join(parts + [self.least_squares.to_text()])

    def table(self, which: str = "ballbar"):
        """The plug-in's table of ``which`` (the thesis' ``ballbar`` or ``probe`` values)."""
        if self.own is None:
            raise AttributeError("this machine's plug-ins give no deterministic identification with tables")
        return self.own.table(which)

    def __getattr__(self, name):
        """The plug-in result's own attributes (the thesis': ``ballbar``, ``probe``, ``checks``, ...)."""
        own = self.__dict__.get("own")
        if own is None or name.startswith("__"):
            raise AttributeError(name)
        return getattr(own, name)


def identify(campaign, data: str) -> Identification:
    """``identify`` on any machine: the least squares of ``campaign``'s ``data`` and the plug-in's own method where
    the machine provides one."""
    from ..machines.plugins import provided

    own = provided(campaign.machine, "identify")
    return Identification(identify_least_squares(campaign, data), None if own is None else own(campaign))
