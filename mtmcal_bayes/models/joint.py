"""Several forward models over one parameter space, stacked: ball-bar eccentricities, then probe readings."""

from __future__ import annotations

import numpy as np

from ..observations import JointObservations


class JointModel:
    """The models ``parts`` (same ``space``) as one: ``(n, p)`` -> ``(n, m₁ + m₂ + …)``.

    ``design`` exists when every part is linear (the stacked design matrices).
    """

    def __init__(self, parts):
        self.parts = list(parts)
        first = self.parts[0]
        self.name, self.campaign, self.space = first.name, first.campaign, first.space
        self.observations = JointObservations(tuple(p.observations for p in self.parts))
        if all(hasattr(p, "design") for p in self.parts):
            self.design = np.vstack([p.design for p in self.parts])

    def predict(self, theta: np.ndarray) -> np.ndarray:
        theta = np.asarray(theta, dtype=float)
        if hasattr(self, "design"):
            return theta @ self.design.T
        return np.concatenate([p.predict(theta) for p in self.parts], axis=-1)

    __call__ = predict
