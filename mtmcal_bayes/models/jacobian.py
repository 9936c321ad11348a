"""The numerical Jacobian of any forward model: the first order every linearisation of the engine uses, and the
complex-step Jacobian of a model analytic in its parameters."""

from __future__ import annotations

import numpy as np


def jacobian(model, theta0: np.ndarray | None = None, steps: np.ndarray | None = None) -> np.ndarray:
    """Central finite-difference Jacobian ``(m, p)`` of ``model.predict`` at ``theta0`` (default zero).

    Default steps: 1″ for angles, 1 µm for lengths; all 2p evaluations in one batch.
    """
    p = len(model.space)
    theta0 = np.zeros(p) if theta0 is None else np.asarray(theta0, float)
    h = model.space.display_scale() if steps is None else np.asarray(steps, float)
    batch = np.concatenate([theta0 + np.diag(h), theta0 - np.diag(h)])
    pred = model.predict(batch)
    return ((pred[:p] - pred[p:]) / (2 * h)[:, None]).T


def complex_step_jacobian(model, step: float = 1e-20) -> np.ndarray:
    """The Jacobian ``(m, p)`` of ``model.predict`` at zero by the complex step: ``Im f(i·h·e_j) / h`` per column,
    exact to rounding (no difference of nearly equal numbers), all p columns in one batch.  The chain is analytic
    in the deviations and nuisance terms (rotations, translations, a Euclidean length, a least-squares fit)."""
    h = step * model.space.display_scale()
    return (model.predict(1j * np.diag(h)).imag / h[:, None]).T


def jacobian_at_zero(model) -> np.ndarray:
    """The Jacobian ``(m, p)`` of ``model.predict`` at zero, as exactly as the model allows: by the complex step
    where its ``predict`` carries complex parameters (the model states ``complex_step = True``: the chain and its
    first order), else by central differences (:func:`jacobian`)."""
    return complex_step_jacobian(model) if getattr(model, "complex_step", False) else jacobian(model)
