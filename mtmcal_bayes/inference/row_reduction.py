"""Rows of a linear-Gaussian model reduced to their rank where their noise is the same in every cell of the grid.

In :class:`~.marginal.MarginalPosterior`'s model ``y ~ N(c + Aθ, A Σ0 Aᵀ + diag(b + σ_g²))`` the rows that share
their scale ``g`` and their base variance ``b`` (a block: every reading of a run of one instrument, usually) have one
variance ``d = b + σ_g²`` in every cell.  With the block's rows ``A_k = U S Vᵀ`` (thin SVD, rank ``r``) and ``N`` an
orthonormal basis of the rest of its ``n`` dimensions, rotating the block by ``[U N]ᵀ`` changes nothing (an
orthogonal map of readings of equal variance): ``Uᵀ y_k`` has rows ``S Vᵀ`` and variance ``d``, and ``Nᵀ y_k`` is
independent of θ and of every other reading (``Nᵀ A_k = 0``), ``N(Nᵀ c_k, d I)``.  So the posterior of θ in a cell
is the reduced model's, and the cell's likelihood is the reduced model's times

    ``(2π d)^(−(n − r)/2) · exp(−RSS / 2d)``,  ``RSS = ‖r_k − U Uᵀ r_k‖²`` of the residual ``r = y − c − Aμ0``,

the :meth:`RowReduction.log_rest` the reduced posterior's weights take (``log_extra``).  Exact, to rounding.  A
design's check holds 400 simulated campaigns of a few hundred probe and R-test readings whose rank is a few dozen:
its grid of 24³ cells whitens a fifth of the rows.
"""

from __future__ import annotations

import numpy as np


class RowReduction:
    """The blocks of ``A`` ``(m, P)`` with equal ``groups`` and ``base_var`` (both ``(m,)``) reduced to their rank.

    Attributes
    ----------
    A : (m', P) the reduced rows: a block's ``S Vᵀ``, a row of a block not reduced as it is
    base_var : (m',) their base variances, mm²
    groups : (m',) their scales
    """

    def __init__(self, A: np.ndarray, base_var: np.ndarray, groups: np.ndarray):
        A, base_var, groups = np.asarray(A, float), np.asarray(base_var, float), np.asarray(groups, int)
        blocks: dict[tuple[int, float], list[int]] = {}
        for i, key in enumerate(zip(groups.tolist(), base_var.tolist())):
            blocks.setdefault(key, []).append(i)
        tol = np.finfo(float).eps * max(A.shape) * (np.abs(A).max() if A.size else 0.0)
        projections, reduced = [], []  # (rows, (n, r) basis) of each reduced block
        out_rows, out_base, out_groups = [], [], []
        for (g, b), rows in blocks.items():
            rows = np.asarray(rows)
            u, s, vt = np.linalg.svd(A[rows], full_matrices=False)
            r = int(np.sum(s > tol))
            basis = u[:, :r]
            projections.append((rows, basis))
            reduced.append(len(rows) > r)
            out_rows.append(s[:r, None] * vt[:r])
            out_base.append(np.full(r, b))
            out_groups.append(np.full(r, g))
        self._projections = projections
        self._rest = [(rows, basis, groups[rows[0]], base_var[rows[0]]) for (rows, basis), red in
                      zip(projections, reduced) if red]
        self.A = np.vstack(out_rows) if out_rows else np.zeros((0, A.shape[1]))
        self.base_var = np.concatenate(out_base) if out_base else np.zeros(0)
        self.groups = np.concatenate(out_groups).astype(int) if out_groups else np.zeros(0, int)

    def data(self, y: np.ndarray) -> np.ndarray:
        """The reduced readings ``(N, m')`` of readings ``y`` ``(N, m)`` (``Uᵀ y_k`` of each block, in its order)."""
        y = np.atleast_2d(y)
        return np.hstack([y[:, rows] @ basis for rows, basis in self._projections])

    def log_rest(self, residual: np.ndarray, sigma: np.ndarray) -> "RestTerms":
        """The log-likelihood of what the reduction leaves out, per cell ``sigma`` ``(G, s)`` (mm) and residual
        ``residual`` ``(N, m)`` (mm: the readings less the prediction at the prior mean), as :class:`RestTerms`
        (``(G, N)`` by :meth:`RestTerms.dense`)."""
        residual = np.atleast_2d(residual)
        G = len(sigma)
        const, coef, rss = np.zeros(G), np.zeros((G, len(self._rest))), np.zeros((len(self._rest), len(residual)))
        for j, (rows, basis, g, b) in enumerate(self._rest):
            r_k = residual[:, rows]
            rss[j] = np.sum((r_k - (r_k @ basis) @ basis.T) ** 2, axis=1)  # (N,)
            d = b + sigma[:, g] ** 2  # (G,)
            const -= 0.5 * (len(rows) - basis.shape[1]) * np.log(2.0 * np.pi * d)
            coef[:, j] = -0.5 / d
        return RestTerms(const, coef, rss)


class RestTerms:
    """A log-likelihood ``(G, N)`` of ``G`` cells and ``N`` data vectors of the form ``const[:, None] + coef @ rss``:
    ``const`` (G,), ``coef`` (G, k), ``rss`` (k, N) — one matrix product, added where the cells' weights are made
    (:meth:`.marginal.MarginalPosterior.target_moments`), instead of a (G, N) pass per block."""

    def __init__(self, const: np.ndarray, coef: np.ndarray, rss: np.ndarray):
        self.const, self.coef, self.rss = const, coef, rss

    def dense(self) -> np.ndarray:
        """The log-likelihood ``(G, N)``."""
        out = self.coef @ self.rss
        out += self.const[:, None]
        return out


__all__ = ["RowReduction", "RestTerms"]
