"""The numerical Jacobian of any forward model: the first order every linearisation of the engine uses."""

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
