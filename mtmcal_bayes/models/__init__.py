"""Forward models: parameter batches ``(n, p)`` to predicted eccentricities ``(n, m)``."""

from .linear import LinearModel, linear_coefficients

__all__ = ["LinearModel", "linear_coefficients"]
