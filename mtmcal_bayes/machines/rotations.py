"""Exact rotations of batches of vectors: ``expm([ε]×)`` by Rodrigues' formula, for the chain and the thesis' model."""

from __future__ import annotations

import numpy as np


def rotation(rotvec: np.ndarray) -> np.ndarray:
    """Exact rotation matrices ``expm([ε]×)`` for rotation vectors ``(n, 3)`` -> ``(n, 3, 3)`` (Rodrigues).

    ``R = I + sinc(θ)·K + ½·sinc²(θ/2)·K²`` with ``K = [ε]×`` and ``θ = |ε|``: no cancellation for small θ.
    """
    v = np.atleast_2d(np.asarray(rotvec))
    v = v if np.iscomplexobj(v) else v.astype(float)  # complex: a complex-step derivative goes through
    K = np.zeros((len(v), 3, 3), dtype=v.dtype)
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -v[:, 2], v[:, 1], -v[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = v[:, 2], -v[:, 1], v[:, 0]
    with np.errstate(invalid="ignore", over="ignore"):  # absurd angles give NaN, which the callers report
        theta = np.sqrt(np.einsum("ni,ni->n", v, v))
        a = np.sinc(theta / np.pi)[:, None, None]
        b = 0.5 * np.sinc(theta / (2 * np.pi))[:, None, None] ** 2
        return np.eye(3) + a * K + b * (K @ K)


def _apply(R: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Apply per-draw rotations ``(n,3,3)`` to vectors ``(n,3)`` or ``(n,k,3)``."""
    Rt = np.transpose(R, (0, 2, 1))
    if v.ndim == 2:
        return (v[:, None, :] @ Rt)[:, 0, :]
    return v @ Rt  # batched matmul: far faster than einsum here
