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
    exact to rounding (no difference of nearly equal numbers), all columns in one batch.  The chain is analytic
    in the deviations and nuisance terms (rotations, translations, a Euclidean length, a least-squares fit).

    A model that states its Jacobian's structure (``column_support()``, ``(m, p)`` booleans: a ball-bar run's
    readings depend on the deviations and on its own set-up's and mount's terms only) has the columns whose
    supports are disjoint stepped in one evaluation (Curtis–Powell–Reid): each reading's imaginary part is then its
    one column's derivative, computed with the same arithmetic as alone (the other columns enter no operation of
    its), so the Jacobian is the same to the bit, in a few dozen evaluations instead of one per nuisance term."""
    h = step * model.space.display_scale()
    support = model.column_support() if hasattr(model, "column_support") else None
    if support is None:
        return (model.predict(1j * np.diag(h)).imag / h[:, None]).T
    colour = _colours(support)
    steps = np.zeros((int(colour.max()) + 1 if len(colour) else 0, len(h)), dtype=complex)
    steps[colour, np.arange(len(h))] = 1j * h
    im = model.predict(steps).imag  # (colours, m)
    return np.where(support, im[colour].T / h[None, :], 0.0)


def _colours(support: np.ndarray) -> np.ndarray:
    """``(p,)`` a colour per column of ``support`` (m, p), columns of one colour touching disjoint rows: each column
    the first colour whose rows it does not touch (greedy, in column order)."""
    used: list[np.ndarray] = []
    out = np.empty(support.shape[1], dtype=int)
    for j in range(support.shape[1]):
        col = support[:, j]
        for c, rows in enumerate(used):
            if not (rows & col).any():
                rows |= col
                out[j] = c
                break
        else:
            used.append(col.copy())
            out[j] = len(used) - 1
    return out


def jacobian_at_zero(model) -> np.ndarray:
    """The Jacobian ``(m, p)`` of ``model.predict`` at zero, as exactly as the model allows: by the complex step
    where its ``predict`` carries complex parameters (the model states ``complex_step = True``: the chain and its
    first order), else by central differences (:func:`jacobian`)."""
    return complex_step_jacobian(model) if getattr(model, "complex_step", False) else jacobian(model)
