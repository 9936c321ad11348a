"""The posterior of a linear-Gaussian model with its noise scales marginalised on a grid.

For a linear model ``y ~ N(c + Aθ, diag(b + σ_g²))`` with normal priors ``θ ~ N(μ0, diag v0)``,
where each observation belongs to one of ``s`` discrepancy scales ``σ = (σ_1 … σ_s)`` (one per
instrument: ``g`` its group), the posterior with σ unknown is a mixture over σ of Gaussian
posteriors, weighted by the marginal likelihood ``p(y | σ)·p(σ)``.  :class:`MarginalPosterior`
evaluates it on a quadrature grid, the product of one grid per scale: :data:`GRID` cells for one
scale, :data:`GRID_2D` per scale for two, each of equal width on ``[lo, hi]`` and represented by its
midpoint.  ``hi`` is the prior's 0.99999 quantile, or beyond it where the data put σ, or below it where the data
put the whole posterior of a single scale within :data:`FINE` of those cells (:func:`sigma_range`); ``lo`` is 0 unless the data put σ far from it.  A prior that vanishes at 0 (the
log-normal of a σ_model learnt elsewhere) has its mass away from 0 and, with a large log sd, a long tail: its
grid runs where the posterior is, both ends found by the scan, in cells of equal width in log σ (each cell
weighted by its width), which keep the bulk resolved however long the tail (equal widths in σ gave sds 2–5 %
off for a log sd of 0.7–1).  The moments of θ are then exact
to the quadrature error, below 1e-3 of the posterior sd (tests: coarse against fine grids; with three scales,
48³ cells against 72³ on the nutating head's demo and the trunnion with every instrument: against 80³ and 96³ they
were 2e-8 sd apart, though the demo's scales are piled against 0).
From three scales on (:data:`BY_SCALE`) each cell's algebra is assembled scale by scale, not cell by cell: the
others' block of the whitening is whitened by blocks in turn, each cell's precision is a sum of one term per
scale, the targets' moments come from the whitened inner products (:meth:`_BlockWhitening.inner_pairs`) and the proposal's
cells are factored when first used (seconds instead of minutes for 110 592 cells).

For the ``linear`` model this is the exact posterior: the reference the sampler is checked
against, the exact sampler of ``sample --sampler exact`` and of simulation-based calibration, and
the Monte-Carlo preposterior of the planner.  For a kinematic model, built on the model
linearised at a point (``A`` its Jacobian, ``c`` its offset), it is the linearised posterior from
which the sampler starts and proposes (:mod:`.approximation`).  Its :meth:`MarginalPosterior.log_evidence`
is the marginal likelihood ``log p(y)`` of the data, by which readings of the data are compared
(:mod:`mtmcal_bayes.posterior.readings`).

:class:`GridProposal` is that mixture for one data vector as a continuous density: a cell drawn
by its weight, σ uniform within it, θ from the cell's Gaussian.  Its draws and log-density make an
independence Metropolis–Hastings proposal.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from .row_reduction import RestTerms

#: quadrature cells of one discrepancy scale
GRID = 128
#: cells per scale when there are two (the grid is their product)
GRID_2D = 48
#: from this many discrepancy scales on (a grid of GRID_2D³ cells and more) each cell's algebra is assembled scale by
#: scale: its precision the sum of one term per scale, its whitened inner products from :meth:`_BlockWhitening.inner_pairs`.
#: The same numbers to rounding; fewer scales keep the cell-by-cell products their published numbers were made with
BY_SCALE = 3
#: largest draws × parameters² of one gathered product in :meth:`GridProposal.draw` (8 MB of Cholesky factors);
#: beyond it the draws are made cell by cell
GATHER_MAX = 1_000_000
#: the scans of :func:`sigma_range` run from this fraction of the prior's 0.99999 quantile to this multiple of
#: the largest plausible scale
SCAN_FROM, SCAN_TO = 1e-3, 10.0
#: the grid covers σ where the log posterior is within this many nats of its maximum
DROP = 30.0
#: a one-scale grid spans the prior's range unless the posterior lies within this many of its cells (then the grid
#: spans the posterior's: the σ of an R-test simulated without discrepancy, 0.06 ± 0.04 µm, lay within 2 of the
#: 128 cells over 0–8.8 µm, its moments 6–8 % off)
FINE = 16
#: a grid cell whose posterior weight for a data vector is below this adds nothing to that vector's moments (at most
#: cells × this of the weight, 1e-14 on 24³ cells) and is left out of them
WEIGHT_FLOOR = 1e-18
#: points of each log-spaced scan of :func:`sigma_range` (about 11 per factor of e over its seven decades)
SCAN_POINTS = 160


def _lower_inverse(L: np.ndarray) -> np.ndarray:
    """Inverse of each lower-triangular matrix of ``L`` ``(G, n, n)``, exactly lower triangular.

    LAPACK's triangular inverse (``dtrtri``), one call per matrix: a sixth of the arithmetic of an inverse by LU
    (which also leaves round-off above the diagonal), 3–8× faster on the grids here even called cell by cell.  A
    C-ordered lower factor is, read in Fortran order, its upper transpose, so each call inverts ``L[g].T`` in place
    of a copy and the result is transposed back."""
    from scipy.linalg import lapack

    out = np.empty_like(L, dtype=float)
    for g in range(len(L)):
        inv_t, info = lapack.dtrtri(np.asarray(L[g], dtype=float).T, lower=0)
        if info:
            raise np.linalg.LinAlgError(f"singular triangular factor (dtrtri info {info})")
        out[g] = inv_t.T
    out[:, *np.triu_indices(L.shape[-1], 1)] = 0.0
    return out


def _lower_solve(L: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``L[g]⁻¹ b`` for each lower-triangular matrix of ``L`` ``(G, n, n)`` and one ``b`` ``(n, k)``; returns
    ``(G, n, k)``.  LAPACK's triangular solve (``dtrtrs``), one call per matrix:
    a general solve would factor each triangular matrix again (3–5× the time here).  As in :func:`_lower_inverse`,
    ``L[g].T`` read in Fortran order is ``L[g]``, solved transposed."""
    from scipy.linalg import lapack

    b = np.asarray(b, dtype=float)
    out = np.empty((len(L),) + b.shape)
    for g in range(len(L)):
        x, info = lapack.dtrtrs(np.asarray(L[g], dtype=float).T, b, lower=0, trans=1)
        if info:
            raise np.linalg.LinAlgError(f"singular triangular factor (dtrtrs info {info})")
        out[g] = x
    return out


def _as_list(value, s: int) -> list:
    """``value`` (one for every scale, or a sequence of ``s``) as a list of ``s``."""
    if isinstance(value, (list, tuple, np.ndarray)):
        if len(value) != s:
            raise ValueError(f"expected {s} values, one per discrepancy scale, got {len(value)}")
        return list(value)
    return [value] * s


def _vanishes_at_zero(prior) -> bool:
    """Whether a scale's prior (frozen scipy distribution) is a log-normal, whose density vanishes at σ = 0 and whose
    mass lies away from it: its grid is spaced in log σ."""
    return getattr(getattr(prior, "dist", None), "name", "") == "lognorm"


def _scale_count(sigma_prior, sigma_fixed, groups) -> int:
    for v in (sigma_prior, sigma_fixed):
        if isinstance(v, (list, tuple, np.ndarray)):
            return len(v)
    return int(np.max(groups)) + 1 if groups is not None and len(groups) else 1


def _dense(log_extra) -> np.ndarray:
    """A ``log_extra`` (G, N) as an array (:class:`.row_reduction.RestTerms` made dense)."""
    return log_extra.dense() if isinstance(log_extra, RestTerms) else log_extra


class _Whitened:
    """The others' block of :class:`_BlockWhitening`'s ``T v`` in every cell of the others, ``(Gb, mb, k)``, kept as
    its :attr:`_BlockWhitening.inner` whitening's :meth:`_BlockWhitening._parts` ``(u, p)``: the others' cell
    ``(i, g)`` (its first scale ``i``) holds ``[u_g ; p_g / sqrt(eigenvalues[i, g])]``, so its norms and inner
    products are sums over ``u`` plus sums over ``p`` weighted by ``1 / eigenvalue``, without the ``n0`` copies of
    ``u`` (hundreds of megabytes for a design's check: 400 campaigns on 24³ cells)."""

    def __init__(self, inner: "_BlockWhitening", parts: tuple):
        self.inner, self.parts = inner, parts

    def sq_norms(self) -> np.ndarray:
        """``(Gb, k)``: each vector's squared norm in each cell."""
        return self.inner.norms_of(self.parts)

    def dot(self, other: "_Whitened") -> np.ndarray:
        """``(Gb, k, t)``: the inner products of these ``k`` vectors with ``other``'s ``t`` in each cell."""
        (u, p), (ux, px) = self.parts, other.parts
        uu = u.dot(ux) if isinstance(u, _Whitened) else np.swapaxes(u, 1, 2) @ ux  # (Gb', k, t) or (1, k, t)
        # the first scale's part: the other's columns (few: targets, a matrix's) over the eigenvalues, per cell
        first = np.swapaxes(p, 1, 2)[None] @ (px[None] / self.inner.eigenvalues[..., None])  # (n0', Gb', k, t)
        return (uu[None] + first).reshape(-1, p.shape[2], px.shape[2])

    def transposed_times(self, other: "_Whitened") -> np.ndarray:
        """``(Gb, t, k)``: ``other``ᵀ times these vectors in each cell (``other`` the whitened columns of a matrix)."""
        return np.swapaxes(self.dot(other), 1, 2)


class _BlockWhitening:
    """A whitening of every grid cell's prior predictive covariance ``S = S0 + diag(base_var + σ[groups]²)`` from
    one eigendecomposition per combination of the other scales' cells, not one factorisation per cell.

    The observations of the first scale (``a``) and of the others (``b``): with the others' block
    ``S_bb = L_b L_bᵀ`` factored (one Cholesky factor per combination of their cells) and ``W = L_b⁻¹ S0_ba``, the
    Schur complement of ``b`` is ``C + σ₀² I`` with ``C = S0_aa + diag(base_var_a) − WᵀW``, and ``C = Q Λ Qᵀ`` once
    serves every cell of the first scale.  ``v ↦ [L_b⁻¹ v_b ; (Λ + σ₀²)^(-1/2) Qᵀ (v_a − Wᵀ L_b⁻¹ v_b)]`` is then a
    linear map ``T`` with ``TᵀT = S⁻¹`` (block LDLᵀ), and ``log det S = 2 Σ log diag L_b + Σ log(Λ + σ₀²)``.  With one
    scale ``b`` is empty: one eigendecomposition for the whole grid.  With three or more ``L_b⁻¹`` is replaced by
    the others' own block whitening (:attr:`inner`, the same construction one scale down): any ``T_b`` with
    ``T_bᵀT_b = S_bb⁻¹`` serves, and ``log det S_bb`` is its ``logdet``.  Another square root of ``S⁻¹`` than a
    Cholesky factor's inverse, so every norm and inner product of whitened vectors (all that is made of them) is
    the same.  The cells are the grid's (first scale slowest, as :class:`MarginalPosterior` orders them)."""

    def __init__(self, S0: np.ndarray, base_var: np.ndarray, sigma: np.ndarray, groups: np.ndarray, *,
                 n_first: int):
        first = groups == 0
        self.a, self.b = np.flatnonzero(first), np.flatnonzero(~first)
        G = len(sigma)
        cells = sigma.reshape(n_first, G // n_first, sigma.shape[1])
        sigma_first, others = cells[:, 0, 0], cells[0]  # (n0,) and (Gb, s): σ of the first scale, of the others
        C = S0[np.ix_(self.a, self.a)] + np.diag(base_var[self.a])
        self.inner = None
        if len(self.b):
            mb = len(self.b)
            groups_b = groups[self.b]
            if (groups_b == 1).any() and (groups_b > 1).any():
                # the others have several scales: their block whitened by blocks in turn (one eigendecomposition
                # per combination of the scales after the second) instead of a Cholesky factor per combination
                # of their cells (48² factors of the others' size on a grid of three scales)
                self.inner = _BlockWhitening(S0[np.ix_(self.b, self.b)], base_var[self.b], others[:, 1:],
                                             groups_b - 1, n_first=len(np.unique(others[:, 1])))
                self.L_b = None
                S0_ba = S0[np.ix_(self.b, self.a)]
                self.W = self.inner(S0_ba)  # (Gb, mb, ma)
                self._W_parts = self.inner._parts(S0_ba)  # W as the inner whitening's parts
                logdet_b = self.inner.logdet
            else:
                S_bb = S0[np.ix_(self.b, self.b)][None] + (base_var[self.b][None] + others[:, groups_b] ** 2
                                                            )[:, :, None] * np.eye(mb)[None]  # (Gb, mb, mb)
                self.L_b = np.linalg.cholesky(S_bb)
                self.W = _lower_solve(self.L_b, S0[np.ix_(self.b, self.a)])  # (Gb, mb, ma)
                logdet_b = 2.0 * np.log(np.diagonal(self.L_b, axis1=1, axis2=2)).sum(axis=1)
            C = C[None] - np.swapaxes(self.W, 1, 2) @ self.W
        else:
            self.L_b = self.W = None
            C, logdet_b = C[None], np.zeros(1)
        lam, self.Q = np.linalg.eigh(C)  # (Gb, ma), (Gb, ma, ma)
        self.eigenvalues = lam[None] + sigma_first[:, None, None] ** 2  # (n0, Gb, ma): of every cell's C + σ₀² I
        self.logdet = (logdet_b[None] + np.log(self.eigenvalues).sum(axis=2)).reshape(G)

    def _whiten_b(self, v_b: np.ndarray) -> np.ndarray:
        """The others' block whitened, ``(Gb, mb, k)`` for ``v_b`` ``(mb, k)``."""
        return self.inner(v_b) if self.inner is not None else _lower_solve(self.L_b, v_b)

    def __call__(self, v: np.ndarray) -> np.ndarray:
        """``T v`` of every cell, ``(G, m, k)``, for ``v`` ``(m, k)``."""
        v_a = v[self.a][None]  # (1, ma, k)
        parts = []
        if self.W is not None:
            u_b = self._whiten_b(v[self.b])  # (Gb, mb, k)
            v_a = v_a - np.swapaxes(self.W, 1, 2) @ u_b
            parts.append(np.broadcast_to(u_b[None], (len(self.eigenvalues),) + u_b.shape))
        z_a = (np.swapaxes(self.Q, 1, 2) @ v_a)[None] / np.sqrt(self.eigenvalues)[..., None]  # (n0, Gb, ma, k)
        out = np.concatenate(parts + [z_a], axis=2)
        return out.reshape(-1, out.shape[2], v.shape[1])

    def _parts(self, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The pieces of ``T v`` ``(m, k)`` that do not depend on the first scale: the others' whitened block ``u``
        ``(Gb, mb, k)`` (``(1, 0, k)`` without others) and ``p = Qᵀ(v_a − Wᵀu)`` ``(Gb, ma, k)``; cell ``(i, g)``'s
        ``T v`` is ``[u_g ; p_g / sqrt(eigenvalues[i, g])]``."""
        v_a = v[self.a][None]
        if self.W is None:
            u_b = np.zeros((1, 0, v.shape[1]))
        elif self.inner is not None:  # u kept as the inner whitening's parts (it is n0 times their size)
            u_b = _Whitened(self.inner, self.inner._parts(v[self.b]))
            v_a = v_a - u_b.transposed_times(_Whitened(self.inner, self._W_parts))
        else:
            u_b = self._whiten_b(v[self.b])
            v_a = v_a - np.swapaxes(self.W, 1, 2) @ u_b
        return u_b, np.swapaxes(self.Q, 1, 2) @ v_a

    def norms(self, v: np.ndarray) -> np.ndarray:
        """``(T v)ᵀ(T v)``'s diagonal ``(G, k)`` of every cell for ``v`` ``(m, k)``, without forming ``T v``."""
        return self.norms_of(self._parts(v))

    def _over_first(self, prod: np.ndarray) -> np.ndarray:
        """``Σ_j prod[g, j, …] / eigenvalues[i, g, j]`` ``(n0, Gb, …)`` of ``prod`` ``(Gb or 1, ma, …)``."""
        inv = 1.0 / self.eigenvalues  # (n0, Gb, ma)
        n0, Gb, ma = inv.shape
        out = np.swapaxes(inv, 0, 1) @ prod.reshape(prod.shape[0], ma, -1)  # (Gb, n0, r)
        return np.swapaxes(out, 0, 1).reshape((n0, Gb) + prod.shape[2:])

    def norms_of(self, parts: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
        """:meth:`norms` ``(G, k)`` from the :meth:`_parts` of ``v``."""
        u, p = parts
        uu = u.sq_norms() if isinstance(u, _Whitened) else np.einsum("gmk,gmk->gk", u, u)
        return (uu[None] + self._over_first(p**2)).reshape(-1, p.shape[2])

    def inner_pairs(self, parts_v: tuple[np.ndarray, np.ndarray], parts_x: tuple[np.ndarray, np.ndarray],
                    cells: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """``(T v[:, cols[q]])ᵀ (T x)`` in cell ``cells[q]`` for each pair ``q``, ``(pairs, t)``, from the
        :meth:`_parts` of ``v`` ``(m, k)`` and ``x`` ``(m, t)``, without forming ``T v`` cell by cell: the others' part
        is the same for every cell of the first scale, the first scale's a sum over the eigenvectors weighted by
        ``1 / eigenvalue`` (the same numbers as from :meth:`__call__`, to rounding)."""
        (u_v, p_v), (u_x, p_x) = parts_v, parts_x
        n0, Gb, ma = self.eigenvalues.shape
        first, other = np.divmod(cells, Gb)
        # the pairs by cell of the others (a radix sort: fewer than 2¹⁵ such cells), each one's in one product, and
        # put back in their order at the end (one gather)
        order = np.argsort(other.astype(np.int16 if Gb < 2**15 else np.int64), kind="stable")
        other, first, cols = other[order], first[order], cols[order]
        uu = u_v.dot(u_x) if isinstance(u_v, _Whitened) else np.swapaxes(u_v, 1, 2) @ u_x  # (Gb, k, t)
        out = uu[other, cols]  # the others' part, gathered
        scaled = p_v[other, :, cols] / self.eigenvalues[first, other]  # (pairs, ma)
        first_part = np.empty_like(out)
        starts = np.flatnonzero(np.r_[True, np.diff(other) != 0])
        for a, b in zip(starts, np.r_[starts[1:], len(order)]):
            np.matmul(scaled[a:b], p_x[other[a]], out=first_part[a:b])
        out += first_part
        back = np.empty_like(order)
        back[order] = np.arange(len(order))
        return out[back]


class MarginalPosterior:
    """The σ-marginal posterior of a linear-Gaussian model on a grid of its discrepancy scales.

    Parameters
    ----------
    A : (m, P) design matrix, mm per internal unit
    base_var : (m,) variance of each mean without the discrepancy scales, mm²
    prior_var : (P,) prior variances, internal units²
    sigma_prior : frozen scipy distribution of the scale (mm), or a list of them, one per scale; None with
        ``sigma_fixed``
    prior_mean : (P,) prior means (default zero)
    offset : (m,) prediction at θ = 0, mm (default zero: a linear, not affine, model)
    sigma_fixed : the scales known, mm (one value for all, or one per scale): one cell of zero width
    sigma_max : upper end of each scale's grid, mm (one value or one per scale; default :func:`sigma_range`'s
        upper end when ``y`` is given, else the prior's 0.99999 quantile)
    sigma_min : lower end of each scale's grid, mm (default 0, or :func:`sigma_range`'s lower end with ``y``)
    groups : (m,) which scale each observation has (default: all the first)
    y : (m,) the data, to fit the grid to where they put the scales (:func:`sigma_range`)
    cells : cells per scale (default :data:`GRID` for one scale, :data:`GRID_2D` for two or more)

    Attributes
    ----------
    sigma : (G, s) the grid's cells (midpoints), mm
    edges : per scale, the cell edges ``(G_k + 1,)``, mm
    """

    def __init__(self, A: np.ndarray, base_var: np.ndarray, prior_var: np.ndarray, sigma_prior=None, *,
                 prior_mean: np.ndarray | None = None, offset: np.ndarray | None = None,
                 sigma_fixed=None, sigma_max=None, sigma_min=None, groups: np.ndarray | None = None,
                 y: np.ndarray | None = None, cells: int | None = None):
        m, P = A.shape
        self.A = A
        self.prior_var = np.asarray(prior_var, dtype=float)
        self.base_var = np.asarray(base_var, dtype=float)
        self.prior_mean = np.zeros(P) if prior_mean is None else np.asarray(prior_mean, dtype=float)
        self.offset = np.zeros(m) if offset is None else np.asarray(offset, dtype=float)
        s = _scale_count(sigma_prior, sigma_fixed, groups)
        self.groups = np.zeros(m, dtype=int) if groups is None else np.asarray(groups, dtype=int)
        self.n_scales = s
        if sigma_fixed is not None:
            fixed = np.array(_as_list(sigma_fixed, s), dtype=float)
            self.edges = tuple(np.array([f, f]) for f in fixed)
            self.sigma = fixed[None, :]
            self.log_prior = np.zeros(1)
            self.fixed = True
        else:
            priors = _as_list(sigma_prior, s)
            if y is not None and (sigma_max is None or sigma_min is None):
                lo, hi = sigma_range(A, self.base_var, self.prior_var, priors, y=y, prior_mean=self.prior_mean,
                                     offset=self.offset, groups=self.groups)
            else:
                lo = [float(p.ppf(1e-5)) if _vanishes_at_zero(p) else 0.0 for p in priors]
                hi = [float(p.ppf(0.99999)) for p in priors]
            lo = lo if sigma_min is None else _as_list(sigma_min, s)
            hi = hi if sigma_max is None else _as_list(sigma_max, s)
            cells = cells or (GRID if s == 1 else GRID_2D)
            in_log = [_vanishes_at_zero(p) and a > 0 for p, a in zip(priors, lo)]
            self.edges = tuple((np.geomspace if g else np.linspace)(a, b, cells + 1) for a, b, g in zip(lo, hi, in_log))
            mids = [0.5 * (e[:-1] + e[1:]) for e in self.edges]  # the prior may be infinite at 0
            mesh = np.meshgrid(*mids, indexing="ij")
            self.sigma = np.stack([g.ravel() for g in mesh], axis=-1)  # (G, s)
            self.log_prior = sum(p.logpdf(self.sigma[:, k]) for k, p in enumerate(priors))
            if any(in_log):  # cells of unequal width: each weighted by its width (its share of the prior's mass)
                widths = np.meshgrid(*[np.diff(e) for e in self.edges], indexing="ij")
                self.log_prior = self.log_prior + sum(np.log(w.ravel()) for w in widths)
            self._log_cell = None if any(in_log) else sum(math.log(e[1] - e[0]) for e in self.edges)
            self.fixed = False
        self._by_scale = s >= BY_SCALE and not self.fixed
        S = (A * self.prior_var) @ A.T  # (m, m) prior predictive covariance of the means, without noise
        self._whitened_once = False
        self._last_joint: tuple[bytes, np.ndarray] | None = None  # the last residuals' log_joint
        if (self.groups == 0).any():  # the first scale has observations: whitened by blocks (_BlockWhitening)
            self._blocks = _BlockWhitening(S, self.base_var, self.sigma, self.groups, n_first=len(self.edges[0]) - 1)
            self.S_chol = None
            self.S_logdet = self._blocks.logdet
        else:
            self._blocks = None
            self.S_chol = np.linalg.cholesky(S[None] + self.V[:, :, None] * np.eye(m)[None])  # (G, m, m)
            self.S_logdet = 2.0 * np.log(np.diagonal(self.S_chol, axis1=1, axis2=2)).sum(axis=1)

    @functools.cached_property
    def V(self) -> np.ndarray:
        """Each cell's variance of each mean, ``(G, m)``, mm² (made when first needed: 130 MB on a grid of three
        scales, where only some cells' are)."""
        return self._variances(slice(None))

    def _variances(self, cells) -> np.ndarray:
        """The rows ``cells`` (indices or a slice) of :attr:`V`."""
        return self.base_var[None, :] + self.sigma[cells][:, self.groups] ** 2

    @functools.cached_property
    def _whitening(self) -> np.ndarray:
        """``L⁻¹`` of every cell, ``(G, m, m)`` (``L`` the Cholesky factor of the prior predictive covariance): made
        once, so that each data vector and target is whitened by a product, not by a factorisation of its own."""
        if self._blocks is not None:  # the block whitening as a matrix (:meth:`_whiten`)
            return self._blocks(np.eye(len(self.base_var)))
        return _lower_inverse(self.S_chol)

    @functools.cached_property
    def _precision(self) -> np.ndarray:
        """Each cell's posterior precision ``(G, P, P)`` (:meth:`_precision_of`)."""
        return self._precision_of(None)

    def _precision_of(self, cells: np.ndarray | None) -> np.ndarray:
        """The posterior precision ``Σ0⁻¹ + Aᵀ V⁻¹ A`` of the grid cells ``cells`` (indices; None: all), ``(k, P, P)``.
        Every cell: one matrix product (``V⁻¹`` ``(G, m)`` times the rows' outer products ``(m, P²)``).  Some cells:
        one product per cell, so that a cell's precision does not depend on which others it is made with (a large
        product's rounding does): a draw is then the same whatever was drawn before (simulation-based calibration's
        results are identical, bit for bit, whatever the number of workers)."""
        m, P = self.A.shape
        prior = np.diag(1.0 / self.prior_var)[None]
        if self._by_scale:  # the sum of each scale's term at the cell's σ of that scale
            index = np.unravel_index(np.arange(len(self.sigma)) if cells is None else cells, self._shape)
            out = np.repeat(prior, len(index[0]), axis=0)
            for k, term in enumerate(self._scale_precisions):
                out += term[index[k]]
            return out
        if cells is None:
            outer = (self.A[:, :, None] * self.A[:, None, :]).reshape(m, P * P)
            return prior + ((1.0 / self.V) @ outer).reshape(-1, P, P)
        return prior + (self.A.T[None] / self._variances(cells)[:, None, :]) @ self.A

    @property
    def _shape(self) -> tuple[int, ...]:
        """Cells per scale."""
        return tuple(len(e) - 1 for e in self.edges)

    @functools.cached_property
    def _scale_precisions(self) -> list[np.ndarray]:
        """Each scale's term ``A_kᵀ V_k⁻¹ A_k`` of the posterior precision at each of its cells, ``(n_k, P, P)``
        (``A_k`` the rows of its observations, ``V_k`` their variances with the cell's σ_k)."""
        out = []
        for k, e in enumerate(self.edges):
            rows = self.groups == k
            mids = 0.5 * (e[:-1] + e[1:])
            V = self.base_var[rows][None] + mids[:, None] ** 2  # (n_k, m_k)
            out.append((self.A[rows].T[None] / V[:, None, :]) @ self.A[rows])
        return out

    @functools.cached_property
    def _posterior_cells(self) -> tuple[np.ndarray, np.ndarray]:
        """Each cell's posterior covariance ``(G, P, P)`` and gain ``(G, P, m)`` (mean = μ0 + gain @ residual): made
        when first needed (draws, means), not for the evidence or the moments of a few targets."""
        cov = np.linalg.inv(self._precision)
        cov = 0.5 * (cov + np.swapaxes(cov, 1, 2))
        return cov, cov @ (self.A.T[None] / self.V[:, None, :])  # Aᵀ V⁻¹ of every cell (G, P, m)

    def cov_factors(self, cells: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """The lower Cholesky factor ``C`` of the posterior covariance (``C Cᵀ = Σ``) of each cell of ``cells``
        (indices; None: every cell) and its inverse, both ``(k, P, P)``, from the precision without forming Σ: with
        the precision factored "upper-first", ``Σ⁻¹ = U Uᵀ`` (``U`` upper triangular: the Cholesky factor of the
        precision with its order reversed),
        ``Σ = U⁻ᵀ U⁻¹`` and ``C = U⁻ᵀ`` is lower triangular, so it is Σ's Cholesky factor, and ``C⁻¹ = Uᵀ``.
        One factorisation and one triangular inverse instead of an inverse, a factorisation and an inverse."""
        precision = self._precision if cells is None else self._precision_of(cells)
        U = np.linalg.cholesky(precision[:, ::-1, ::-1])[:, ::-1, ::-1]  # precision = U Uᵀ
        inv = np.swapaxes(U, 1, 2)  # C⁻¹ = Uᵀ, lower triangular
        return _lower_inverse(inv), inv

    def _cell_factors(self, cells: np.ndarray) -> np.ndarray:
        """The covariance factors ``C`` (:meth:`cov_factors`) of ``cells``, ``(k, P, P)``: each cell factored when
        first drawn from and kept (one grid serves many data vectors in simulation-based calibration)."""
        if "_factors" not in self.__dict__:
            P = self.A.shape[1]
            self._factors = (np.empty((len(self.sigma), P, P)), np.zeros(len(self.sigma), dtype=bool))
        store, have = self._factors
        new = cells[~have[cells]]
        if len(new):
            store[new] = self.cov_factors(new)[0]
            have[new] = True
        return store[cells]

    def means_from_factors(self, y: np.ndarray, chol: np.ndarray, cells: np.ndarray | None = None) -> np.ndarray:
        """Posterior mean of θ in each cell of ``cells`` (None: all) for one data vector ``y`` (m,), ``(k, P)``, from
        their covariance factors ``chol`` (:meth:`cov_factors`): ``μ0 + C Cᵀ Aᵀ V⁻¹ r`` without the gain matrices."""
        V = self.V if cells is None else self._variances(cells)
        b = (self._residual(y[None]) / V) @ self.A  # (k, P): Aᵀ V⁻¹ r of every cell
        return self.prior_mean + np.einsum("gij,gj->gi", chol, np.einsum("gji,gj->gi", chol, b))

    @property
    def cov(self) -> np.ndarray:
        """Posterior covariance of θ in each cell, ``(G, P, P)``."""
        return self._posterior_cells[0]

    @property
    def gain(self) -> np.ndarray:
        """``(G, P, m)``: the posterior mean of θ in each cell is ``μ0 + gain @ residual``."""
        return self._posterior_cells[1]

    def _residual(self, y: np.ndarray) -> np.ndarray:
        """Data minus the prediction at the prior mean, ``(N, m)``."""
        return np.atleast_2d(y) - self.offset - self.A @ self.prior_mean

    def _whiten(self, r: np.ndarray, extra: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray | None]:
        """``L⁻¹ rᵀ`` ``(G, m, N)`` of residuals ``r`` (N, m) and ``L⁻¹ extra`` ``(G, m, k)`` of ``extra`` (m, k) in
        every cell.  ``L⁻¹`` is made on the second use and multiplied from then on; a first use (an evidence, a
        proposal's weights, the moments of a few targets) solves for both at once, which costs less than ``L⁻¹``.
        Mostly the whitening is :class:`_BlockWhitening`'s instead of ``L⁻¹`` (another square root of the same
        ``S⁻¹``), applied at once."""
        if self._blocks is not None:
            out = self._blocks(r.T if extra is None else np.concatenate([r.T, extra], axis=1))  # (G, m, N + k)
            return out[..., : len(r)], None if extra is None else out[..., len(r):]
        if "_whitening" in self.__dict__ or self._whitened_once:
            W = self._whitening
            return W @ r.T, None if extra is None else W @ extra
        self._whitened_once = True
        rhs = r.T if extra is None else np.concatenate([r.T, extra], axis=1)
        out = _lower_solve(self.S_chol, rhs)
        return out[..., : len(r)], None if extra is None else out[..., len(r):]

    def _joint_of_whitened(self, r: np.ndarray, z: np.ndarray) -> np.ndarray:
        """:meth:`log_joint` ``(G, N)`` from the residuals ``r`` (N, m) and their whitened ``z`` (G, m, N); kept for
        the same residuals' next call (the evidence, weights and moments of one data vector each ask for it)."""
        return self._joint_of_norms(r, np.sum(z**2, axis=1))

    def _joint_of_norms(self, r: np.ndarray, zz: np.ndarray) -> np.ndarray:
        """:meth:`_joint_of_whitened` from the squared norms ``zz`` (G, N) of the whitened residuals."""
        loglik = -0.5 * (zz + self.S_logdet[:, None] + r.shape[1] * np.log(2 * np.pi))
        joint = loglik + self.log_prior[:, None]
        self._last_joint = (r.tobytes(), joint)
        return joint.copy()

    def log_joint(self, y: np.ndarray) -> np.ndarray:
        """``log p(y | σ) + log p(σ)`` of every cell, ``(G, N)``, for data ``y`` of shape ``(N, m)``."""
        r = self._residual(y)
        if self._last_joint is not None and self._last_joint[0] == r.tobytes():
            return self._last_joint[1].copy()
        if self._by_scale and self._blocks is not None:
            return self._joint_of_norms(r, self._blocks.norms(r.T))
        return self._joint_of_whitened(r, self._whiten(r)[0])

    def weights(self, y: np.ndarray, log_extra: np.ndarray | None = None) -> np.ndarray:
        """Posterior weights of the grid, ``(G, N)`` for data ``y`` of shape ``(N, m)``; ``log_extra`` ``(G, N)`` or its
        :class:`.row_reduction.RestTerms`: a log-likelihood of each cell from readings not among the rows
        (:meth:`.row_reduction.RowReduction.log_rest`)."""
        lj = self.log_joint(y)
        return self._normalised(lj if log_extra is None else lj + _dense(log_extra))

    def _weights_of_norms(self, r: np.ndarray, zz: np.ndarray, log_extra) -> np.ndarray:
        """:meth:`weights` ``(G, N)`` from the squared norms ``zz`` (G, N) of the whitened residuals ``r`` (N, m),
        made in ``zz``'s memory (a design's check: 24³ cells × 400 campaigns, each pass over them counts);
        ``log_extra`` a (G, N) log-likelihood, or its :class:`.row_reduction.RestTerms`, or None."""
        const = self.log_prior - 0.5 * (self.S_logdet + r.shape[1] * np.log(2 * np.pi))  # (G,)
        lw = zz
        lw *= -0.5
        if isinstance(log_extra, RestTerms):
            lw += log_extra.coef @ log_extra.rss
            const = const + log_extra.const
        elif log_extra is not None:
            lw += log_extra
        lw += const[:, None]
        return self._normalised(lw)

    @staticmethod
    def _normalised(lw: np.ndarray) -> np.ndarray:
        """Each column of the log-weights ``lw`` (G, N) made weights summing to one, in ``lw``'s memory (every caller
        passes an array of its own)."""
        lw -= lw.max(axis=0)
        np.exp(lw, out=lw)
        lw /= lw.sum(axis=0)
        return lw

    def log_evidence(self, y: np.ndarray) -> float:
        """The marginal likelihood ``log p(y)`` of one data vector ``y`` (m,) (density of the means, mm⁻ᵐ):
        the grid's quadrature of ``p(y | σ) p(σ)`` over the scales (at the fixed scales when they are fixed)."""
        lj = self.log_joint(np.asarray(y)[None])[:, 0]
        if self.fixed:
            return float(lj[0])
        top = lj.max()
        return float(top + np.log(np.exp(lj - top).sum()) + (self._log_cell or 0.0))

    def means(self, y: np.ndarray) -> np.ndarray:
        """Posterior mean of θ in each cell, ``(G, N, P)``."""
        return self.prior_mean + np.einsum("gpm,nm->gnp", self.gain, self._residual(y))

    def posterior_mean(self, y: np.ndarray) -> np.ndarray:
        """Posterior mean of θ ``(P,)`` given one data vector ``y`` (m,): the cells' means weighted by the cells'
        posterior weights.  From three scales on by :meth:`target_moments` of θ itself, which never forms the
        cells' gains (``(G, P, m)``: gigabytes on 110 592 cells)."""
        y = np.asarray(y)
        if self._by_scale:
            return self.target_moments(y[None], np.eye(self.A.shape[1]))[0][0]
        w = self.weights(y[None])[:, 0]
        return np.einsum("g,gp->p", w, self.means(y[None])[:, 0])

    def target_moments(self, y: np.ndarray, T: np.ndarray, log_extra: np.ndarray | None = None, *,
                       with_weights: bool = False) -> tuple[np.ndarray, ...]:
        """Posterior mean and sd of the targets ``T @ θ``, each ``(N, t)``, for data ``(N, m)`` (``log_extra`` as
        in :meth:`weights`); ``with_weights``: and the cells' weights ``(G, N)`` they were made with.

        In the data's space, which costs the ``t`` targets rather than the ``P`` parameters: with ``K = Σ0 Aᵀ``
        and ``S`` a cell's prior predictive covariance, ``E[Tθ] = Tμ0 + T K S⁻¹ r`` and
        ``Var[Tθ] = T Σ0 Tᵀ − T K S⁻¹ Kᵀ Tᵀ`` (the same as from the cell's posterior of θ; a test holds them equal)."""
        TK = (T * self.prior_var) @ self.A.T  # (t, m)
        r = self._residual(y)
        # the inner products of the whitened, scale by scale: from three scales on, and for many data vectors (a
        # design's check: 400 simulated campaigns on 48² cells would whiten gigabytes cell by cell)
        prior_sd2 = np.sum((T * self.prior_var) * T, axis=1)  # (t,)
        if self._blocks is not None and (self._by_scale or len(r) > 1):
            parts_r, parts_x = self._blocks._parts(r.T), self._blocks._parts(TK.T)
            w = self._weights_of_norms(r, self._blocks.norms_of(parts_r), log_extra)  # (G, N)
            # the cells' means only where their weight counts: each vector's posterior of the scales lies in a few
            # hundred of 24³ cells, and the rest (at most G × WEIGHT_FLOOR of its weight) moves no moment
            n, cells = np.nonzero(w.T > WEIGHT_FLOOR)  # the pairs, by vector
            mean_q = (T @ self.prior_mean)[None] + self._blocks.inner_pairs(parts_r, parts_x, cells, n)  # (pairs, t)
            w_q = w[cells, n][:, None]
            starts = np.flatnonzero(np.r_[True, np.diff(n) != 0])  # every vector has its heaviest cell
            mean = np.add.reduceat(w_q * mean_q, starts, axis=0)
            var_g = prior_sd2[None] - self._blocks.norms_of(parts_x)  # (G, t)
            second = np.add.reduceat(w_q * mean_q**2, starts, axis=0) + w.T @ var_g
            return (mean, np.sqrt(np.maximum(second - mean**2, 0.0))) + ((w,) if with_weights else ())
        Z, X = self._whiten(r, TK.T)  # (G, m, N): L⁻¹ r; (G, m, t): L⁻¹ KᵀTᵀ
        lj = self._joint_of_whitened(r, Z)  # (G, N)
        w = self._normalised(lj if log_extra is None else lj + _dense(log_extra))
        mean_g = (T @ self.prior_mean)[None, None, :] + np.swapaxes(Z, 1, 2) @ X  # (G, N, t)
        var_g = prior_sd2[None] - np.sum(X**2, axis=1)  # (G, t)
        mean = np.einsum("gn,gnt->nt", w, mean_g)
        second = np.einsum("gn,gnt->nt", w, mean_g**2 + var_g[:, None, :])
        return (mean, np.sqrt(np.maximum(second - mean**2, 0.0))) + ((w,) if with_weights else ())

    def sigma_moments(self, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Posterior mean and sd of each scale, each ``(s,)`` mm, for one data vector ``y`` (m,)."""
        w = self.weights(y[None])[:, 0]
        mean = w @ self.sigma
        return mean, np.sqrt(np.maximum(w @ self.sigma**2 - mean**2, 0.0))

    def draw(self, y: np.ndarray, n: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """``n`` draws ``(theta (n, P), sigma (n, s))`` from the posterior given data ``y`` (m,): a cell by its weight,
        σ uniform within it (not its midpoint: a truth is ranked among continuous draws), θ from the cell's Gaussian."""
        w = self.weights(y[None])[:, 0]
        g = rng.choice(len(self.sigma), size=n, p=w)
        used = np.unique(g)
        chol = self._cell_factors(used)
        means = self.means_from_factors(y, chol, used)
        theta = np.empty((n, self.A.shape[1]))
        for k, cell in enumerate(used):  # the draws of numpy's multivariate_normal with the Cholesky factor
            idx = np.flatnonzero(g == cell)
            theta[idx] = means[k] + rng.standard_normal((len(idx), theta.shape[1])) @ chol[k].T
        if self.fixed:
            return theta, self.sigma[g]
        index = np.unravel_index(g, tuple(len(e) - 1 for e in self.edges))
        low = np.stack([e[i] for e, i in zip(self.edges, index)], axis=-1)
        width = np.stack([e[i + 1] - e[i] for e, i in zip(self.edges, index)], axis=-1)
        return theta, low + width * rng.random(low.shape)


def sigma_range(A: np.ndarray, base_var: np.ndarray, prior_var: np.ndarray, sigma_priors, *, y: np.ndarray,
                prior_mean: np.ndarray | None = None, offset: np.ndarray | None = None,
                groups: np.ndarray | None = None, drop: float = DROP) -> tuple[list[float], list[float]]:
    """Lower and upper end of each scale's grid, mm: where the marginal posterior of the scales given ``y`` has
    fallen ``drop`` nats below its maximum, on a log-spaced scan of each scale with the others at their best
    (two passes); for one scale the upper end at least the prior's 0.99999 quantile (a model that cannot fit the
    data puts σ in the prior's far tail, and the grid follows it) unless the posterior lies within :data:`FINE` of
    that grid's cells (data without discrepancy put σ near 0: the scan's end then, or too few cells resolve it), for two the scan's alone (each has GRID_2D cells:
    spread over the prior's range they would be too few where the posterior is); the lower end 0 unless the data
    keep σ well away from 0.

    A log-normal prior, whose density vanishes at 0, is scanned from far below its 0.00001 quantile, and both its
    ends are the scan's (the lower one above 0, for a grid spaced in log σ): its 0.99999 quantile may lie far beyond
    the posterior (a log sd of 1 puts it at 70× the median), and the data do not need it."""
    priors = list(sigma_priors) if isinstance(sigma_priors, (list, tuple)) else [sigma_priors]
    s = len(priors)
    m, P = A.shape
    groups = np.zeros(m, dtype=int) if groups is None else np.asarray(groups, dtype=int)
    r = y - (np.zeros(m) if offset is None else offset) - A @ (np.zeros(P) if prior_mean is None else prior_mean)
    S0 = (A * prior_var) @ A.T
    prior_hi = [float(p.ppf(0.99999)) for p in priors]
    away = [_vanishes_at_zero(p) for p in priors]
    # one scale: its grid of GRID cells spans the prior's range at least; two: GRID_2D cells each, where the data
    # put them (48 cells over the prior's 0–8.8 µm left 3 for a σ_model_probe of 0.2 ± 0.1 µm, whose draws came
    # out 9 % wide and whose midpoint moments 7 % narrow)
    floor = [0.0 if a or s > 1 else h for a, h in zip(away, prior_hi)]
    spread = float(np.sqrt(np.mean(r**2)))
    scans = [np.geomspace(min(hi, float(p.ppf(1e-5))) * SCAN_FROM if a else hi * SCAN_FROM,
                          max(hi, 10.0 * spread) * SCAN_TO, SCAN_POINTS) for hi, p, a in zip(prior_hi, priors, away)]

    def scan(k: int, others: np.ndarray) -> np.ndarray:
        """log p(σ | y) up to a constant, ``(SCAN_POINTS,)``, along ``scans[k]`` with the other scales at
        ``others`` ``(s,)``: the scan as a grid whose first scale is scale ``k`` (its other scales one cell each),
        whitened by :class:`_BlockWhitening` (one eigendecomposition for every point of the scan)."""
        order = [k] + [j for j in range(s) if j != k]  # scale k first
        sig = np.repeat(others[None], len(scans[k]), axis=0)
        sig[:, k] = scans[k]
        blocks = _BlockWhitening(S0, base_var, sig[:, order], np.argsort(order)[groups], n_first=len(scans[k]))
        z = blocks(r[:, None])[..., 0]
        with np.errstate(divide="ignore"):
            lp = sum(p.logpdf(sig[:, j]) for j, p in enumerate(priors))
        return -0.5 * (np.sum(z**2, axis=1) + blocks.logdet) + lp

    best = np.array([float(p.median()) for p in priors])
    lo, hi = [0.0] * s, list(floor)
    for _ in range(2 if s > 1 else 1):
        for k in range(s):
            logp = scan(k, best)
            above = np.flatnonzero(logp >= logp.max() - drop)
            best[k] = scans[k][int(np.argmax(logp))]
            end = float(scans[k][min(above[-1] + 1, len(scans[k]) - 1)])
            # data that put the whole posterior of a scale near 0 (an instrument without discrepancy) would leave it
            # a few of the prior-wide grid's cells, whose midpoints then miss its moments: the grid follows the data
            hi[k] = max(floor[k] if end > floor[k] * FINE / GRID else 0.0, end)
            lo[k] = float(scans[k][max(above[0] - 1, 0)]) if away[k] else (
                0.0 if above[0] == 0 else float(scans[k][above[0] - 1]))
    return lo, hi


def sigma_upper(A, base_var, prior_var, sigma_prior, *, y, prior_mean=None, offset=None, drop: float = DROP) -> float:
    """Upper end of a one-scale grid covering the posterior of σ given ``y``, mm (:func:`sigma_range`)."""
    return sigma_range(A, base_var, prior_var, [sigma_prior], y=y, prior_mean=prior_mean, offset=offset,
                       drop=drop)[1][0]


class GridProposal:
    """The grid posterior of one data vector as a continuous density of ``(θ, σ)``.

    A cell ``j`` drawn with probability ``w_j``, each scale uniform within it, θ ~ N(μ_j, Σ_j);
    ``log g(θ, σ)`` is that density for the cell holding σ (−inf beyond the grid); with fixed scales
    there is one cell and no σ dimension.  Only the cells of some weight (:attr:`kept`) are ever drawn, so
    only theirs are factored: ``chol``, ``chol_inv``, ``mean`` and ``log_det`` are indexed by a cell's
    :attr:`slot` (−1 for a cell not factored; :attr:`cells` the cell of each slot).  Below :data:`BY_SCALE`
    scales every kept cell is factored at once (its slot its place among the kept cells); from there on (tens of
    thousands of kept cells, a sampler draws from a few thousand) each when first drawn or evaluated, into the
    next free slot of arrays allocated but not written until then: the factored cells fill the arrays' beginning,
    so only the memory they use is ever touched (scattered slots touched nearly all of 360 MB on the nutating
    head's demo, numpy giving such arrays huge pages).  No heavier-tailed defensive component is
    mixed in: on the thesis campaign it cost 10 % of the effective sample size and, in 24 dimensions, did not
    rescue a proposal that was badly wrong (the acceptance stayed near zero either way).  A poor
    proposal shows instead as a low independence acceptance, the differential-evolution moves carry
    the chains, and R-hat and ESS decide as usual.
    """

    def __init__(self, marginal: MarginalPosterior, y: np.ndarray):
        self.fixed = marginal.fixed
        w = marginal.weights(y[None])[:, 0]
        keep = w > 1e-12 * w.max()  # cells of no weight are never drawn; their density is −inf
        self.cell_prob = np.where(keep, w, 0.0) / w[keep].sum()  # (G,)
        with np.errstate(divide="ignore"):
            self.log_cell_prob = np.log(self.cell_prob)
        self.edges = marginal.edges
        self.shape = tuple(len(e) - 1 for e in self.edges)
        self.sigma = marginal.sigma
        index = np.unravel_index(np.arange(len(self.sigma)), self.shape)
        self.low = np.stack([e[i] for e, i in zip(self.edges, index)], axis=-1)  # (G, s)
        self.width = np.stack([e[i + 1] - e[i] for e, i in zip(self.edges, index)], axis=-1)
        self.kept = np.flatnonzero(keep)  # (K,) the cells ever drawn
        self.slot = np.full(len(w), -1)
        self._marginal, self._y = marginal, y
        if marginal._by_scale:  # factored when first needed (:meth:`_slots`)
            K, self.P = len(self.kept), marginal.A.shape[1]
            self.chol, self.chol_inv = np.empty((K, self.P, self.P)), np.empty((K, self.P, self.P))
            self.mean, self.log_det = np.empty((K, self.P)), np.empty(K)
            self.cells = np.full(K, -1)
            self._have = np.zeros(K, dtype=bool)
        else:
            self.slot[self.kept] = np.arange(len(self.kept))
            self.cells = self.kept
            self.chol, self.chol_inv = marginal.cov_factors(self.kept)  # (K, P, P) each
            self.mean = marginal.means_from_factors(y, self.chol, self.kept)  # (K, P)
            self.log_det = 2.0 * np.log(np.diagonal(self.chol, axis1=1, axis2=2)).sum(axis=1)
            self.P = self.mean.shape[1]
            self._have = np.ones(len(self.kept), dtype=bool)

    def _slots(self, cells: np.ndarray) -> np.ndarray:
        """The slots ``(n,)`` of the kept grid cells ``cells`` (n,), those not factored yet factored into the next
        free slots."""
        new = np.unique(cells[self.slot[cells] < 0])
        if len(new):
            done = int(self._have.sum())
            slots = np.arange(done, done + len(new))
            chol, self.chol_inv[slots] = self._marginal.cov_factors(new)
            self.chol[slots] = chol
            self.mean[slots] = self._marginal.means_from_factors(self._y, chol, new)
            self.log_det[slots] = 2.0 * np.log(np.diagonal(chol, axis1=1, axis2=2)).sum(axis=1)
            self.slot[new], self.cells[slots], self._have[slots] = slots, new, True
        return self.slot[cells]

    def draw(self, n: int, random) -> tuple[np.ndarray, np.ndarray]:
        """``n`` draws ``(theta (n, P), sigma (n, s))``; ``random`` a numpy RandomState (emcee's)."""
        j = random.choice(self.cell_prob.size, size=n, p=self.cell_prob)
        sigma = (self.low[j] + self.width[j] * random.rand(n, self.low.shape[1]) if not self.fixed
                 else np.repeat(self.sigma, n, axis=0))
        z = random.randn(n, self.P)
        k = self._slots(j)
        if n * self.P**2 <= GATHER_MAX:  # a sampler's proposals (walkers × P²): one batched product
            return self.mean[k] + np.einsum("nij,nj->ni", self.chol[k], z), sigma
        theta = np.empty((n, self.P))
        # many draws: one product per grid cell drawn (at most G), not a gathered (n, P, P) stack (20 000 draws of
        # 40 parameters would gather 250 MB)
        for cell in np.unique(k):
            rows = k == cell
            theta[rows] = self.mean[cell] + z[rows] @ self.chol[cell].T
        return theta, sigma

    def logpdf(self, theta: np.ndarray, sigma: np.ndarray | None) -> np.ndarray:
        """Log-density ``(n,)`` of ``theta`` (n, P) and ``sigma`` (n, s) (without σ when the scales are fixed)."""
        n = len(theta)
        if self.fixed:
            j = np.zeros(n, dtype=int)
            inside = np.ones(n, dtype=bool)
            log_width = np.zeros(n)
        else:
            sigma = np.asarray(sigma, dtype=float).reshape(n, -1)
            idx, inside = [], np.ones(n, dtype=bool)
            for k, e in enumerate(self.edges):
                idx.append(np.clip(np.searchsorted(e, sigma[:, k], side="right") - 1, 0, len(e) - 2))
                inside &= (sigma[:, k] >= e[0]) & (sigma[:, k] < e[-1])
            j = np.ravel_multi_index(tuple(idx), self.shape)
            log_width = np.log(self.width[j]).sum(axis=1)
        inside &= self.cell_prob[j] > 0  # a cell of no weight: density −inf
        k = self._slots(np.where(inside, j, self.kept[0]))
        u = np.einsum("nij,nj->ni", self.chol_inv[k], theta - self.mean[k])
        r2 = np.einsum("ni,ni->n", u, u)
        log_norm = -0.5 * self.log_det[k] - 0.5 * self.P * math.log(2 * math.pi)
        return np.where(inside, self.log_cell_prob[j] + log_norm - 0.5 * r2 - log_width, -np.inf)
