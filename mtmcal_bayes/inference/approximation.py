"""Where the posterior is before sampling: the σ-marginal posterior of the forward model linearised at its mode.

For the ``linear`` model with normal priors this *is* the posterior
(:class:`~.marginal.MarginalPosterior`, exact to its quadrature).  For the
kinematic models the model is linearised by Gauss–Newton: Jacobian at the
prior mean, then again at the linearised posterior mean; their nonlinearity is
below 0.1 µm at thesis magnitudes, against a noise of 0.5–2 µm, so the
approximation is close.  Non-normal priors (campaign overrides) are replaced by
normals of the same mean and sd.

The sampler uses it three ways: its draws are the walkers' starting points
(nothing to forget), it is the proposal of an independence Metropolis–Hastings
move (:class:`IndependenceMove`: the acceptance test keeps the result exact
whatever the approximation), and its moments are the reference of the accuracy
check — the exact posterior for ``linear``, model-form information (how far the
kinematic posterior is from its linearisation) for the ``htm-*`` models.

Everything is in the sampler's coordinates ``z`` of :class:`~.log_posterior.LogPosterior`:
``(θ − centre)/width`` and ``log(σ/scale)`` for each discrepancy scale.
"""

from __future__ import annotations

import emcee
import numpy as np

from .. import units
from ..models import jacobian
from ..parameters import QUANTITIES, quantity_unit, weights
from .log_posterior import LogPosterior
from .marginal import GridProposal, MarginalPosterior

#: Gauss–Newton linearisations of a kinematic model (the second moves the point by well under the noise)
LINEARISATIONS = 2


class PosteriorApproximation:
    """The linearised σ-marginal posterior of ``post`` (see the module docstring).

    Attributes
    ----------
    exact : whether it is the posterior itself (linear model, normal priors)
    marginal : the :class:`MarginalPosterior` over the forward parameters
    proposal : its :class:`GridProposal` for the campaign's data
    """

    def __init__(self, post: LogPosterior):
        self.post = post
        priors = post.priors.priors[: post.p]
        mean0 = np.array([q.mean for q in priors])
        var0 = np.array([q.sd for q in priors]) ** 2
        normal = all(q.dist == "normal" for q in priors)
        sigma_prior = [q.frozen() for q in post.priors.priors[post.p:]] if post.fixed_sigma is None else None
        base_var, y = post.likelihood.base_var, post.likelihood.y

        def marginal_at(A, c):
            return MarginalPosterior(A, base_var, var0, sigma_prior, prior_mean=mean0, offset=c,
                                     sigma_fixed=None if sigma_prior else [post.fixed_sigma] * len(post.scales),
                                     groups=post.scale_of, y=y)

        model = post.forward
        if hasattr(model, "design"):  # linear: the design matrix is the model
            self.marginal = marginal_at(model.design, np.zeros(len(y)))
            self.exact = normal
        else:
            theta0 = mean0
            for _ in range(LINEARISATIONS):
                A = jacobian(model, theta0)
                self.marginal = marginal_at(A, model.predict(theta0) - A @ theta0)
                theta0 = self.marginal.posterior_mean(y)
            self.exact = False
        self.proposal = GridProposal(self.marginal, y)
        self.kind = ("exact σ-marginal posterior" if self.exact else
                     "linearised posterior" + (" (normal priors of the same mean and sd)" if not normal else ""))

    # ------------------------------------------------------------ in sampling coordinates
    def draw_z(self, n: int, random) -> np.ndarray:
        """``n`` draws in sampling coordinates ``(n, q)``; ``random`` a numpy RandomState."""
        theta, sigma = self.proposal.draw(n, random)
        if self.post.fixed_sigma is None:
            theta = np.column_stack([theta, sigma])
        return self.post.to_z(theta)

    def logpdf_z(self, z: np.ndarray) -> np.ndarray:
        """Log-density ``(n,)`` of sampling coordinates ``(n, q)``, up to a constant."""
        post = self.post
        theta = post.to_theta(z)
        if post.fixed_sigma is not None:
            return self.proposal.logpdf(theta, None)
        sigma = theta[:, post.p:]
        with np.errstate(divide="ignore"):  # d log σ: density in log σ is σ times that in σ
            return self.proposal.logpdf(theta[:, : post.p], sigma) + np.log(sigma).sum(axis=1)

    def independence_move(self) -> IndependenceMove:
        return IndependenceMove(self)

    # ------------------------------------------------------------ reference moments
    def moments(self, names) -> dict[str, tuple[float, float]]:
        """Mean and sd (display units) of each quantity of ``names`` the approximation has."""
        post = self.post
        space = list(post.space.names)
        out = {}
        rows, kept = [], []
        for name in names:
            if name in QUANTITIES or name in space:  # the thesis' quantities, or a described machine's deviations
                w = weights(name, space)
                if not w:
                    continue
                row = np.zeros(post.p)
                for k, v in w.items():
                    row[space.index(k)] = v
                rows.append(row)
                kept.append(name)
        y = post.likelihood.y[None]
        if rows:
            mean, sd = self.marginal.target_moments(y, np.array(rows))
            for i, name in enumerate(kept):
                unit = quantity_unit(name)
                out[name] = (units.from_internal(mean[0, i], unit), units.from_internal(sd[0, i], unit))
        if post.fixed_sigma is None and any(n in names for n in post.scales):
            m, s = self.marginal.sigma_moments(post.likelihood.y)
            for k, n in enumerate(post.scales):
                if n in names:
                    out[n] = (units.from_internal(m[k], "um"), units.from_internal(s[k], "um"))
        return out


class IndependenceMove(emcee.moves.MHMove):
    """Metropolis–Hastings with proposals drawn from a :class:`PosteriorApproximation`, whatever the walker's position.

    The Hastings factor ``log g(x) − log g(x′)`` makes the move exact for any proposal;
    ``accepted / proposed`` counts how often the approximation was good enough.
    """

    def __init__(self, approximation: PosteriorApproximation):
        super().__init__(self._propose)
        self.approximation = approximation
        self.proposed = 0
        self.accepted = 0

    def _propose(self, coords: np.ndarray, random) -> tuple[np.ndarray, np.ndarray]:
        a = self.approximation
        new = a.draw_z(len(coords), random)
        return new, a.logpdf_z(coords) - a.logpdf_z(new)

    def propose(self, model, state):
        state, accepted = super().propose(model, state)
        self.proposed += len(accepted)
        self.accepted += int(np.sum(accepted))
        return state, accepted

    @property
    def acceptance(self) -> float:
        return self.accepted / self.proposed if self.proposed else float("nan")
