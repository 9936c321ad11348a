"""A whole campaign's expected posterior, fast enough to search over (SPEC §16, docs/design.md).

A design is a count ``n_k`` of runs of each candidate ``k`` (0 … :data:`MAX_INSTANCES`).  The first
run of a candidate is the candidate as it is (its setup's and mount's nuisance offsets shared with
every run there); each further run is on a W-ball placement of its own, whose offsets are
integrated out (they add ``X_W X_Wᵀ`` to that run's noise covariance, as in
:meth:`Planner._trace_new_runs`).

σ_model is unknown.  The criterion is evaluated at :data:`NODE_LEVELS` quantiles ``σ_s`` of its
current distribution (its prior where its instrument has no measured reading, else its exact posterior given every
measured reading, :class:`.design_now.Now`).  At a fixed σ the linear model's
posterior is exact and does not depend on the data, so in the parameters' prior-sd coordinates
(``X = A·diag(prior sd)``) every run adds ``Xᵀ N⁻¹ X`` to the precision ``I + M₁`` and the moments
``Mⱼ = Xᵀ N⁻ʲ X`` (j = 1, 2, 3) and ``t = tr N⁻²`` from which the Fisher information about σ,
``I(σ) = 2σ² tr C⁻²``, follows by Woodbury (:func:`.design.trace_inv_sq`).  Per node:

* the target sds ``sd_t(σ_s) = sqrt(T′ (I + M₁)⁻¹ T′ᵀ)``;
* the σ_model contraction by Laplace, ``1 − 1/(1 + var_prior·I(σ_s))`` (under a prior learnt elsewhere,
  ``var_prior`` the learnt prior's and the contraction measured against the wider of the assumed and the learnt
  prior's variance, :func:`.design.sigma_contraction`).

A target is *promised* when ``sd_t`` at the :data:`PROMISE` quantile of σ meets it (``sd_t`` grows
with σ, so that is the sd met in that share of machines, before the extra spread of σ being learnt
from the data; :mod:`.design_check` measures the realised share by exact Monte Carlo).  The
contraction is the average over the nodes.  All candidates are evaluated in one batched inverse.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from .. import units
from ..inference.marginal import MarginalPosterior
from .design import Planner, sigma_contraction
from .design_now import now_of, prior_means, taught_prior
from .determined import SUBSPACE_TOL, Determination

#: most runs of one candidate in a design (each further one on its own W-ball placement)
MAX_INSTANCES = 3
#: a design differing from the last one summed in full in at most this many candidates is summed from it
NEAR = 32
#: steps from one design to the next (:meth:`DesignProblem.moments`) before the moments are summed in full again
REFRESH = 64
#: quantiles of σ_model at which the criterion is evaluated
NODE_LEVELS = (0.1, 0.3, 0.5, 0.7, 0.9)
#: the share of machines for which a design promises its targets: the sd is taken at this quantile of σ_model
PROMISE = 0.9


@dataclass
class DesignValue:
    """The criterion of one or many designs (leading axis ``B``).

    ``sd_nodes`` (B, S, t) target sds at the σ nodes, display units; ``contraction_nodes`` (B, S);
    ``undetermined`` (B, t) of the watched targets (:attr:`DesignProblem.watch`) the part the design's runs do not
    see, 0 where they determine it (:meth:`.determined.Determination.unseen`; None: none watched).
    """

    sd_nodes: np.ndarray
    contraction_nodes: np.ndarray
    undetermined: np.ndarray | None = None

    @property
    def sd_promised(self) -> np.ndarray:
        """(B, t) the sd at the :data:`PROMISE` quantile of σ_model."""
        return self.sd_nodes[:, NODE_LEVELS.index(PROMISE)]

    @property
    def sd_mean(self) -> np.ndarray:
        """(B, t) the sd averaged over σ_model."""
        return self.sd_nodes.mean(axis=1)

    @property
    def contraction(self) -> np.ndarray:
        """(B,) the σ_model contraction averaged over σ_model."""
        return self.contraction_nodes.mean(axis=1)


def sigma_nodes(planner: Planner, levels=NODE_LEVELS, instrument: str = "ballbar") -> np.ndarray:
    """``instrument``'s discrepancy scale (mm) at ``levels`` of its current distribution: its prior where the
    campaign has no measured reading of it, else its exact σ-marginal posterior given every measured reading
    (:class:`.design_now.Now`)."""
    return now_of(planner).quantiles(instrument, levels)


def current_posterior(planner: Planner) -> MarginalPosterior:
    """The exact σ-marginal posterior of the planner's measured readings, its data fitted into the grid
    (:class:`.design_now.Now`; with the ball bar's readings alone over every column of the planner)."""
    return now_of(planner).posterior


def _unseen(norms: np.ndarray, watch: np.ndarray) -> np.ndarray:
    """(B, t) the unseen part of the watched targets, 0 where determined (:data:`.determined.SUBSPACE_TOL`)."""
    return np.where(watch[None] & (norms > SUBSPACE_TOL), norms, 0.0)


#: singular values of a candidate's rows below this fraction of its largest are dropped by :func:`_compressed`
RANK_TOL = 1e-12


def _compressed(X: np.ndarray, w: np.ndarray, compress: bool) -> tuple[np.ndarray, np.ndarray, int]:
    """A candidate's rows ``X`` (r, P') and weights ``w`` (r,), as few rows as their rank where ``compress`` (a probe
    or R-test run: tens of rows, one weight for all) and the number of rows dropped.

    With one noise variance ``c`` for all its rows everything the criterion takes of a run is invariant under
    ``X → UᵀX`` (``X = U·R``, ``U`` orthonormal columns spanning ``X``'s): ``XᵀN⁻ʲX``, the Woodbury updates
    (``W⁻¹ = U W′⁻¹ Uᵀ + (I − UUᵀ)/c``) and, with its own terms integrated out, ``Xᵀ(cI + X_w X_wᵀ)⁻¹X``; only
    ``tr N⁻²`` counts every row (``dropped · c⁻²`` added back).  So a run is its ``R = S·Vᵀ`` (SVD), at most as many
    rows as the parameters it touches, and the batched updates are padded to that, not to a sweep's 108 rows."""
    if not compress or len(X) == 0 or not np.allclose(w, w[0], rtol=1e-12, atol=0.0):
        return X, w, 0
    _, sv, vt = np.linalg.svd(X, full_matrices=False)
    k = int(np.sum(sv > RANK_TOL * sv[0])) if sv.size and sv[0] > 0 else 0
    k = max(k, 1)
    return sv[:k, None] * vt[:k], np.full(k, w[0]), len(X) - k


def _plus(M: np.ndarray, d: float, term: np.ndarray, *, fresh: bool) -> np.ndarray:
    """``M + d·term`` into a new array (``fresh``: ``M`` is kept) or into ``M``: for ``d`` = ±1 an addition or a
    subtraction, one pass and no temporary (the same floats as ``M + d * term``)."""
    out = None if fresh else M
    if d == 1.0:
        return np.add(M, term, out=out)
    if d == -1.0:
        return np.subtract(M, term, out=out)
    return np.add(M, d * term, out=out)


def _inv_powers(N: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``N⁻¹, N⁻², N⁻³`` of a batch of symmetric positive definite matrices ``(..., r, r)``."""
    Ni = np.linalg.inv(N)
    N2 = Ni @ Ni
    return Ni, N2, N2 @ Ni


class DesignProblem:
    """Candidates, their contributions at the σ nodes, and the criterion of any count vector.

    Parameters
    ----------
    planner : :class:`.design.Planner` over the campaign (the measured readings of the design's instruments,
        :func:`.design_now.measured_data`) and the candidates
    nodes : σ_model values (S,), mm (default :func:`sigma_nodes`)
    """

    def __init__(self, planner: Planner, nodes: np.ndarray | None = None, taught: str = "ballbar"):
        self.planner = planner
        self.candidates = planner.candidates
        #: the instrument whose discrepancy scale is learnt and integrated out (:mod:`.design_instruments`); the
        #: others' rows at the rms of their priors, as the planner's
        self.taught = taught
        self.watch = None  # (the property below)
        self._anchor = None  # (counts (K,), M, t) of the last design summed in full (:meth:`moments`)
        self.nodes = sigma_nodes(planner, instrument=taught) if nodes is None else np.asarray(nodes, float)
        if taught == "ballbar":
            self.sigma_prior_var = float(planner.sigma_prior().var())
            self.sigma_reference_var = planner.contraction_reference()  # None: the prior's
        else:
            self.sigma_prior_var = float(taught_prior(planner, taught).var())
            self.sigma_reference_var = None
        fixed = {i: planner.fixed_scale(i) for i in ("ballbar", "probe", "rtest")}
        scale = np.sqrt(planner.prior_var)
        rows = planner.candidate_rows()
        self._rows = [A for A, _ in rows]
        self._determination = None
        s2 = self.nodes**2  # (S,)
        X0 = planner.A * scale
        cols = np.any(X0 != 0.0, axis=0)
        for A, _ in rows:
            cols |= np.any(A != 0.0, axis=0)
        self.cols = np.flatnonzero(cols)
        X0 = X0[:, self.cols]
        self.Tp = (planner.T * scale)[:, self.cols]  # (t, P')
        # the parameters no row touches keep their prior: their share of each target's variance, (t,)
        self.var_untouched = np.sum(np.delete(planner.T * scale, self.cols, axis=1) ** 2, axis=1)
        to_display = np.array([units.from_internal(1.0, u) for u in planner.target_units])
        self.to_display = to_display
        P = len(self.cols)
        # the measured readings of the learnt scale's instrument: their noise follows it; the others' at their fixed
        # scales (the rms of their priors) enter M₁ only (nothing about the learnt scale in them)
        learnt_rows = planner.row_instrument == taught
        N0 = (planner.V[learnt_rows] - fixed[taught] ** 2)[None, :] + s2[:, None]  # (S, m)
        X0l = X0[learnt_rows]
        self.base = [np.einsum("mp,sm,mq->spq", X0l, N0 ** -j, X0l) for j in (1, 2, 3)]  # each (S, P, P)
        self.base_t = np.sum(N0 ** -2.0, axis=1)  # (S,)
        if not learnt_rows.all():
            Xf = X0[~learnt_rows]
            self.base[0] = self.base[0] + np.einsum("mp,m,mq->pq", Xf, 1.0 / planner.V[~learnt_rows], Xf)[None]
        K, S = len(rows), len(self.nodes)
        self.first = np.zeros((3, K, S, P, P))
        self.again = np.zeros((3, K, S, P, P))
        self.first_t = np.zeros((K, S))
        self.again_t = np.zeros((K, S))
        parts = [_compressed((A * scale)[:, self.cols], w, c.instrument != "ballbar")
                 for (A, w), c in zip(rows, self.candidates)]
        r_max = max((len(X) for X, _, _ in parts), default=1)
        # the candidates by instrument, each group's updates at its own largest rank (a probe's or an R-test's
        # compressed rows are tens where a ball-bar run's are two or three: padded to theirs, every ball-bar
        # candidate's update cost as much); with the ball bar alone one group at r_max, as before
        self._groups = []
        for instrument in dict.fromkeys(c.instrument for c in self.candidates):
            idx = np.array([k for k, c in enumerate(self.candidates) if c.instrument == instrument])
            self._groups.append((idx, max(len(parts[k][0]) for k in idx)))
        # low-rank factors of each run, padded to r_max rows (zero rows, unit noise): rows X (K, r, P) and noise
        # N, N⁻², N⁻³ (K, S, r, r) of a first run (f) and a further one (a), for :meth:`value_plus_one`
        self.Xf, self.Xa = np.zeros((K, r_max, P)), np.zeros((K, r_max, P))
        self.Nf = np.broadcast_to(np.eye(r_max), (K, S, r_max, r_max)).copy()
        self.Na = self.Nf.copy()
        self.D2f, self.D3f = np.zeros_like(self.Nf), np.zeros_like(self.Nf)
        self.D2a, self.D3a = np.zeros_like(self.Nf), np.zeros_like(self.Nf)
        names = planner.space.parameters
        for k, ((Xc, w, dropped), c) in enumerate(zip(parts, self.candidates)):
            learnt = c.instrument == taught  # its rows' noise follows the learnt scale; else fixed at its rms
            base_c = 1.0 / w - fixed[c.instrument] ** 2  # (r,)
            Nc = base_c[None, :] + s2[:, None] if learnt else np.broadcast_to(1.0 / w, (len(s2), len(w)))  # (S, r)
            # the scale's Fisher information comes from the rows whose noise it is: ∂C/∂σ = 2σ·D, D their indicator,
            # so N⁻², N⁻³ and tr N⁻² of the others' rows are left out of M₂, M₃ and t
            # Xᵀ N⁻ʲ X at every node as one batched product (an einsum over three operands is several times slower)
            self.first[0, k] = (Xc.T[None] * (Nc ** -1)[:, None, :]) @ Xc
            if learnt:
                for j in (2, 3):
                    self.first[j - 1, k] = (Xc.T[None] * (Nc ** -j)[:, None, :]) @ Xc
                self.first_t[k] = np.sum(Nc ** -2.0, axis=1) + dropped * Nc[:, 0] ** -2.0
            renewed = c.renewed()
            own = np.array([(names[i].group, names[i].owner) in renewed for i in self.cols], dtype=bool)
            Xw = Xc[:, own]
            Xr = np.where(own[None, :], 0.0, Xc)
            Nr = np.einsum("sr,rq->srq", Nc, np.eye(len(base_c))) + (Xw @ Xw.T)[None]
            powers = _inv_powers(Nr)
            for j, Nj in enumerate(powers if learnt else powers[:1]):
                self.again[j, k] = Xr.T[None] @ Nj @ Xr
            r = len(base_c)
            self.Xf[k, :r], self.Xa[k, :r] = Xc, Xr
            self.Nf[k, :, :r, :r] = np.einsum("sr,rq->srq", Nc, np.eye(r))
            self.Na[k, :, :r, :r] = Nr
            if learnt:
                self.again_t[k] = np.trace(powers[1], axis1=1, axis2=2) + dropped * Nc[:, 0] ** -2.0
                self.D2f[k, :, :r, :r] = np.einsum("sr,rq->srq", Nc ** -2.0, np.eye(r))
                self.D3f[k, :, :r, :r] = np.einsum("sr,rq->srq", Nc ** -3.0, np.eye(r))
                self.D2a[k, :, :r, :r], self.D3a[k, :, :r, :r] = powers[1], powers[2]

    # ------------------------------------------------------------------ criterion
    def moments(self, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(M (3, B, S, P, P), t (B, S))`` of designs ``counts`` (B, K); the caller does not write into them.

        One design within :data:`NEAR` candidates of the last one asked (the search's next step, a drop or a swap)
        is that one's sum plus the changed candidates' terms, and becomes the next one's start, up to
        :data:`REFRESH` steps from a full sum (the rounding of the additions and subtractions stays within a few
        ulps): a search asks thousands of such designs, and a full sum reads every used candidate's (3, S, P, P)
        terms."""
        counts = np.atleast_2d(counts)
        if len(counts) == 1 and self._anchor is not None:
            c0, M0, t0, steps = self._anchor
            changed = np.flatnonzero(counts[0] != c0)
            if len(changed) <= NEAR and steps < REFRESH:
                M, t = M0, t0
                for k in changed:
                    new, old = int(counts[0, k]), int(c0[k])
                    d_first, d_again = float(new >= 1) - float(old >= 1), max(new - 1, 0) - max(old - 1, 0)
                    for d, term, term_t in ((d_first, self.first, self.first_t), (d_again, self.again, self.again_t)):
                        if d:  # each addition one pass, into a new array first, then in place
                            M = _plus(M, d, term[:, k][:, None], fresh=M is M0)
                            t = t + d * term_t[k]
                if len(changed):
                    self._anchor = (counts[0].copy(), M, t, steps + 1)
                return M, t
        M, t = self._summed(counts)
        if len(counts) == 1:
            self._anchor = (counts[0].copy(), M, t, 0)
        return M, t

    def _summed(self, counts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`moments` of ``counts`` (B, K) summed over every candidate they run."""
        # the candidates some design runs (a design runs a few of a hundred: the others' terms are not read)
        K = len(self.candidates)
        used = np.flatnonzero(counts.any(axis=0))
        if 2 * len(used) >= K:  # most of them: every candidate's terms read in place, not a copy of the used ones'
            used = np.arange(K)
        counts = counts[:, used]
        first = (counts >= 1).astype(float)
        again = np.maximum(counts - 1, 0).astype(float)
        # candidates × everything else, one matmul (every candidate: a view, no copy)
        flat = lambda a, idx: a.reshape(3, K, -1)[:, idx] if len(idx) < K else a.reshape(3, K, -1)  # noqa: E731
        shape = (3, len(counts)) + self.first.shape[2:]
        M = np.stack(self.base)[:, None] + (first @ flat(self.first, used)).reshape(shape)
        twice = np.flatnonzero(again.any(axis=0))  # the candidates run more than once (few): their further runs
        if len(twice):
            M = M + (again[:, twice] @ flat(self.again, used[twice])).reshape(shape)
        t = self.base_t[None] + first @ self.first_t[used] + again @ self.again_t[used]
        return M, t

    @property
    def determination(self) -> Determination:
        """What the campaign plus any set of the candidates determines (:class:`.determined.Determination`)."""
        if self._determination is None:
            self._determination = Determination(self.planner, self._rows)
        return self._determination

    @property
    def watch(self) -> np.ndarray | None:
        """(t,) the targets whose determination by the design's runs is part of the criterion (None: none): a target
        the prior alone meets is met only once the runs determine it (:mod:`.determined`)."""
        return self._watch

    @watch.setter
    def watch(self, value) -> None:
        self._watch = None if value is None else np.asarray(value, dtype=bool)
        #: (n, K) the supports of designs found to determine every watched target (:meth:`_covered`)
        self._complete = np.zeros((0, len(self.candidates)), dtype=bool)

    def _undetermined(self, counts: np.ndarray) -> np.ndarray:
        """(B, t) :attr:`DesignValue.undetermined` of designs ``counts`` (B, K)."""
        counts = np.atleast_2d(counts)
        out = np.zeros((len(counts), len(self.watch)))
        for b, c in enumerate(counts):
            if not self._covered(c > 0):
                out[b] = _unseen(self.determination.unseen(c), self.watch)
                if not out[b].any():
                    self._complete = np.vstack([self._complete, c > 0])
        return out

    def _undetermined_plus_one(self, counts: np.ndarray) -> np.ndarray:
        """(K, t) :attr:`DesignValue.undetermined` of ``counts`` (K,) plus one run of each candidate."""
        if not self._undetermined(counts)[0].any():  # a further run keeps them determined
            return np.zeros((len(self.candidates), len(self.watch)))
        return _unseen(self.determination.unseen_plus_one(counts), self.watch)

    def _covered(self, support: np.ndarray) -> bool:
        """Whether the candidates of ``support`` (K,) include those of a design known to determine every watched
        target: adding rows only shrinks the null space, so they determine them too (no null space made)."""
        return bool(np.any(np.all(support[None] | ~self._complete, axis=1)))

    def _watched(self) -> bool:
        return self.watch is not None and bool(np.any(self.watch))

    def value(self, counts: np.ndarray) -> DesignValue:
        """The criterion of designs ``counts`` (B, K) or (K,)."""
        M, t = self.moments(counts)
        v = self._value(M, t)
        if self._watched():
            v.undetermined = self._undetermined(counts)
        return v

    def _value(self, M: np.ndarray, t: np.ndarray) -> DesignValue:
        P = M.shape[-1]
        Sinv = np.linalg.inv(np.eye(P) + M[0])  # (B, S, P, P): posterior covariance, prior-sd coordinates
        var = np.sum((Sinv @ self.Tp.T) * self.Tp.T, axis=-2) + self.var_untouched  # (B, S, t)
        sd = np.sqrt(np.maximum(var, 0.0)) * self.to_display
        G = Sinv @ M[1]
        # traces of products of symmetric matrices as element sums: tr(AB) = Σ A∘B, tr(GG) = Σ G∘Gᵀ
        tr = t - 2.0 * np.sum(Sinv * M[2], axis=(-2, -1)) + np.sum(G * np.swapaxes(G, -1, -2), axis=(-2, -1))
        return DesignValue(sd, self._contraction(tr))

    def _contraction(self, tr: np.ndarray) -> np.ndarray:
        """σ_model's contraction at each node ``(…, S)`` from ``tr(C⁻²)``-like traces ``tr`` (…, S): the Fisher
        information ``2σ²·tr`` (:func:`.design.sigma_contraction`)."""
        fisher = 2.0 * self.nodes**2 * np.maximum(tr, 0.0)
        return sigma_contraction(fisher, self.sigma_prior_var, self.sigma_reference_var)

    def value_plus_one(self, counts: np.ndarray, *,
                       contraction_met: float | None = None) -> tuple[DesignValue, np.ndarray]:
        """The criterion of ``counts`` plus one more run of each candidate ``k`` (K designs) and which of them are
        allowed (fewer than :data:`MAX_INSTANCES` runs of ``k``).

        Where ``counts``' own σ_model contraction reaches ``contraction_met`` (a goal's), each design's contraction
        is given as ``counts``' own, a lower bound, and its updates are not made: a run added never lowers the
        Fisher information about σ (the smaller design's data are a function of the larger's), so the goal stays
        met, and the updates of the traces are three of the four products with P × P matrices.

        One inverse per σ node for the design as it is; each candidate then by rank-r updates (Woodbury; r rows per
        run: two or three of a ball-bar run, the compressed rank of a probe or R-test run, each instrument's
        candidates at their own largest r), with ``Σ`` the design's posterior covariance, ``X`` the run's rows and ``N`` their noise
        covariance: ``Σ′ = Σ − Z``, ``Z = ΣXᵀ W⁻¹ XΣ``, ``W = N + XΣXᵀ``; the target variances fall by
        ``diag(TZTᵀ)``; with ``Y = Xᵀ N⁻² X`` and ``A = Σ M₂``, ``Σ′(M₂ + Y) = A + ΣXᵀ R`` with
        ``R = N⁻²X − W⁻¹(XΣM₂) − W⁻¹(XΣXᵀ)N⁻²X``, so ``tr((Σ′M₂′)²) = tr A² + 2 tr(R A ΣXᵀ) + tr((R ΣXᵀ)²)`` and
        ``tr(Σ′M₃′) = tr(ΣM₃) + tr(N⁻³ H) − tr(W⁻¹(XΣM₃ΣXᵀ + H N⁻³ H))``, ``H = XΣXᵀ``.  Equal to
        :meth:`value` of each design (``tests/test_design.py``).
        """
        counts = np.asarray(counts)
        st = self._state(counts)
        K, S = len(self.candidates), len(st["Sig"])
        contraction_now = self._contraction_now(counts, st, contraction_met)  # (S,): of counts, or a bound
        traces = contraction_met is None or contraction_now.mean() < contraction_met
        var_new = np.empty((K, S, len(self.Tp)))
        trE2, trSM3_new = np.empty((K, S)), np.empty((K, S))
        for idx, r in self._groups:
            out = self._updates(st, counts[idx] == 0, idx, r, traces=traces)
            var_new[idx] = out[0]
            if traces:
                trE2[idx], trSM3_new[idx] = out[1:]
        sd = np.sqrt(np.maximum(var_new, 0.0)) * self.to_display
        if traces:
            dt = np.where(counts[:, None] == 0, self.first_t, self.again_t)  # (K, S)
            contraction = self._contraction(st["t"][None] + dt - 2.0 * trSM3_new + trE2)
        else:
            contraction = np.broadcast_to(contraction_now, (K, S))
        v = DesignValue(sd, contraction)
        if self._watched():
            v.undetermined = self._undetermined_plus_one(counts)
        return v, counts < MAX_INSTANCES

    def _state(self, counts: np.ndarray) -> dict:
        """``counts``' posterior at the σ nodes and what its rank-r updates start from, kept for the next call with
        the same design (an exchange pass asks it once per run of the design): ``Sig`` (S, P, P), ``M2``, ``M3``,
        ``var`` (S, t), ``t`` (S,), the traces ``A = Σ M₂``, ``trA2``, ``trSM3`` (S,) when first needed
        (:meth:`_traced`), and per candidate group the products with its rows made when first asked (``E``: ``XΣ``
        (S, k·r, P), ``ETp``: ``XΣTpᵀ``, ``H``: ``XΣXᵀ`` (k, S, r, r))."""
        key = counts.tobytes()
        if getattr(self, "_last_state", None) is not None and self._last_state[0] == key:
            return self._last_state[1]
        M, t = self.moments(counts)
        P = M.shape[-1]
        Sig = np.linalg.inv(np.eye(P) + M[0, 0])
        state = dict(Sig=Sig, M2=M[1, 0], M3=M[2, 0], t=t[0],
                     var=np.sum((Sig @ self.Tp.T) * self.Tp.T, axis=-2) + self.var_untouched, groups={})
        self._last_state = (key, state)
        return state

    @staticmethod
    def _traced(st: dict) -> dict:
        """``st`` (:meth:`_state`) with ``A = Σ M₂``, ``tr A²`` and ``tr(Σ M₃)`` (S,), made when first needed (the
        contraction's traces: a search whose contraction goal is met needs them for its exchange only)."""
        if "A" not in st:
            A = st["Sig"] @ st["M2"]
            st.update(A=A, trA2=np.sum(A * np.swapaxes(A, -1, -2), axis=(-2, -1)),
                      trSM3=np.sum(st["Sig"] * st["M3"], axis=(-2, -1)))
        return st

    def _contraction_now(self, counts: np.ndarray, st: dict, contraction_met: float | None) -> np.ndarray:
        """(S,) ``counts``' σ_model contraction at the nodes; where a smaller design (each candidate run no more
        often) is known to reach ``contraction_met``, that design's, a lower bound meeting it too (a run added
        never lowers the Fisher information about σ), without the traces."""
        met = getattr(self, "_met", None)
        if contraction_met is not None and met is not None and met[1].mean() >= contraction_met \
                and np.all(counts >= met[0]):
            return met[1]
        self._traced(st)
        c = self._contraction(st["t"] - 2.0 * st["trSM3"] + st["trA2"])
        if contraction_met is not None and c.mean() >= contraction_met:
            self._met = (counts.copy(), c)
        return c

    def value_swap(self, counts: np.ndarray, k: int, *,
                   contraction_met: float | None = None) -> tuple[DesignValue, np.ndarray]:
        """:meth:`value_plus_one` of ``counts`` less one run of candidate ``k`` (an exchange's swaps out of ``k``:
        ``k`` itself is not allowed).

        Where that smaller design's contraction reaches ``contraction_met`` only the target sds are needed, and they
        come from ``counts``' own products with every candidate's rows (:meth:`_state`) corrected by the run taken
        away, a rank-r term: ``Σ_D = Σ + B_kᵀ V⁻¹ B_k`` (``B_k = X_kΣ``, ``V = N_k − X_kΣX_kᵀ``), so ``XΣ_D = XΣ +
        (XΣX_kᵀ) V⁻¹ B_k`` costs ``r_k`` columns, not a product with a P × P matrix per σ node.  Else as
        :meth:`value_plus_one`.  Equal to it (``tests/test_design.py``)."""
        counts = np.asarray(counts)
        less = counts.copy()
        less[k] -= 1
        st = self._state(counts)
        group = next((idx, r) for idx, r in self._groups if k in idx)
        # the smaller design's own contraction: the downdate of run k with its traces
        _, trE2, trSM3_less = self._updates(st, counts[[k]] == 1, np.array([k]), group[1], sign=-1.0)
        dt = self.first_t[k] if counts[k] == 1 else self.again_t[k]
        contraction_less = self._contraction(st["t"] - dt - 2.0 * trSM3_less[0] + trE2[0])  # (S,)
        if contraction_met is None or contraction_less.mean() < contraction_met:
            v, ok = self.value_plus_one(less, contraction_met=contraction_met)
            ok[k] = False
            return v, ok
        Sig, S = st["Sig"], len(st["Sig"])
        r_k = group[1]
        Xk = (self.Xf if counts[k] == 1 else self.Xa)[k, :r_k]  # (r_k, P): the run taken away
        Nk = (self.Nf if counts[k] == 1 else self.Na)[k][:, :r_k, :r_k]  # (S, r_k, r_k)
        Bk = Xk[None] @ Sig  # (S, r_k, P)
        Vinv = np.linalg.inv(Nk - Bk @ Xk.T)  # (S, r_k, r_k)
        BT = Bk @ self.Tp.T  # (S, r_k, t)
        var_less = st["var"] + np.sum(BT * (Vinv @ BT), axis=-2)
        K = len(self.candidates)
        var_new = np.empty((K, S, len(self.Tp)))
        for idx, r in self._groups:
            fresh = counts[idx] == 0  # as in ``less``: k itself is not a swap's partner
            X, N, E, ETp, H = self._products(st, idx, r, fresh)
            n = len(idx)
            C = np.moveaxis((E @ Xk.T).reshape(S, n, r, r_k), 0, 1)  # (n, S, r, r_k): XΣX_kᵀ
            CV = C @ Vinv[None]
            Q = ETp + CV @ BT[None]  # (n, S, r, t): XΣ_D Tpᵀ
            W = N + H + CV @ np.swapaxes(C, -1, -2)
            var_new[idx] = var_less[None] - np.sum(Q * np.linalg.solve(W, Q), axis=-2)
        v = DesignValue(np.sqrt(np.maximum(var_new, 0.0)) * self.to_display,
                        np.broadcast_to(contraction_less, (K, S)))
        if self._watched():
            v.undetermined = self._undetermined_plus_one(less)
        ok = less < MAX_INSTANCES
        ok[k] = False  # its sds above are of a further run of k (as ``counts`` has it), not of ``less``'s
        return v, ok

    def _products(self, st: dict, idx: np.ndarray, r: int, fresh: np.ndarray):
        """The rows ``X`` (n, r, P) and noise ``N`` (n, S, r, r) of one more run of the candidates ``idx`` (a first
        run where ``fresh``) and their products with :meth:`_state`'s ``Σ``: ``E = XΣ`` (S, n·r, P), ``XΣTpᵀ`` and
        ``XΣXᵀ`` (n, S, r, ·), made once per design and group."""
        key = (idx.tobytes(), fresh.tobytes())
        if key not in st["groups"]:
            first = fresh[:, None, None, None]
            X = np.where(first[..., 0], self.Xf[idx, :r], self.Xa[idx, :r])
            N = np.where(first, self.Nf[idx][:, :, :r, :r], self.Na[idx][:, :, :r, :r])
            Sig = st["Sig"]
            E = X.reshape(len(idx) * r, -1) @ Sig  # (S, n·r, P)
            back = lambda Y: np.moveaxis(Y.reshape(len(Sig), len(idx), r, -1), 0, 1)  # noqa: E731
            st["groups"][key] = (X, N, E, back(E @ self.Tp.T), back(E) @ np.swapaxes(X, -1, -2)[:, None])
        return st["groups"][key]

    def value_minus_one(self, counts: np.ndarray) -> tuple[DesignValue, np.ndarray]:
        """The criterion of ``counts`` less one run of each candidate it runs (a design each, in the order of
        ``np.flatnonzero(counts)``) and those designs ``(B, K)``: by rank-r downdates of ``counts``' posterior, as
        :meth:`value_plus_one` adds (a first run's terms where the candidate runs once, a further run's where more);
        equal to :meth:`value` of each (``tests/test_design.py``).  A search weighs every drop of a design at once."""
        counts = np.asarray(counts)
        used = np.flatnonzero(counts)
        less = np.repeat(counts[None], len(used), axis=0)
        less[np.arange(len(used)), used] -= 1
        st = self._state(counts)
        B, S = len(used), len(st["Sig"])
        var_new = np.empty((B, S, len(self.Tp)))
        trE2, trSM3_new = np.empty((B, S)), np.empty((B, S))
        for idx, r in self._groups:
            at = np.flatnonzero(np.isin(used, idx))  # the drops of this group's candidates
            if len(at):
                var_new[at], trE2[at], trSM3_new[at] = self._updates(st, counts[used[at]] == 1, used[at], r,
                                                                     sign=-1.0)
        dt = np.where(counts[used, None] == 1, self.first_t[used], self.again_t[used])  # (B, S)
        v = DesignValue(np.sqrt(np.maximum(var_new, 0.0)) * self.to_display,
                        self._contraction(st["t"][None] - dt - 2.0 * trSM3_new + trE2))
        if self._watched():
            v.undetermined = self._undetermined(less)
        return v, less

    def _updates(self, st: dict, fresh: np.ndarray, idx: np.ndarray, r: int, *, traces: bool = True,
                 sign: float = 1.0):
        """The rank-``r`` updates of :meth:`value_plus_one` of the design whose :meth:`_state` is ``st`` for the
        candidates ``idx`` (their first run where ``fresh``): the target variances ``(k, S, t)`` and, with
        ``traces``, ``tr((Σ′M₂′)²)`` and ``tr(Σ′M₃′)`` ``(k, S)``.  With ``sign`` −1 the run is taken away
        (:meth:`value_minus_one`): the precision gains ``sign·XᵀN⁻¹X``, so ``W = sign·N + XΣXᵀ`` and every term of
        the run's own moments changes sign."""
        # every product with a P × P matrix as one matrix product per σ node over all candidates' rows stacked
        # (k·r, P), then back to (k, S, r, ·) (:meth:`_products`): the batched small products left are r × r, r × P
        Sig = st["Sig"]
        X, N, XS_flat, Q, H = self._products(st, idx, r, fresh)
        first = fresh[:, None, None, None]
        k = len(X)
        back = lambda Y: np.moveaxis(Y.reshape(len(Sig), k, r, -1), 0, 1)  # noqa: E731  (S, k·r, n) -> (k, S, r, n)
        XS = back(XS_flat)
        XSt = np.swapaxes(XS, -1, -2)
        Winv = np.linalg.inv(sign * N + H)
        var_new = st["var"][None] - np.sum(Q * (Winv @ Q), axis=-2)
        if not traces:
            return (var_new,)
        M2, M3, A = st["M2"], st["M3"], self._traced(st)["A"]
        D2 = np.where(first, self.D2f[idx][:, :, :r, :r], self.D2a[idx][:, :, :r, :r])
        D3 = np.where(first, self.D3f[idx][:, :, :r, :r], self.D3a[idx][:, :, :r, :r])
        D2X = D2 @ X[:, None]  # (k, S, r, P)
        R = sign * D2X - Winv @ back(XS_flat @ M2) - sign * (Winv @ (H @ D2X))
        XSA = back(XS_flat @ np.swapaxes(A, -1, -2))  # (k, S, r, P): (AΣXᵀ)ᵀ
        RX = R @ XSt  # (k, S, r, r)
        trE2 = st["trA2"][None] + 2.0 * np.einsum("ksrp,ksrp->ks", R, XSA) + np.einsum("ksij,ksji->ks", RX, RX)
        XSM3XS = back(XS_flat @ M3) @ XSt
        trSM3_new = (st["trSM3"][None] + sign * np.einsum("ksij,ksji->ks", D3, H)
                     - np.einsum("ksij,ksji->ks", Winv, XSM3XS + sign * (H @ D3 @ H)))
        return var_new, trE2, trSM3_new

    def value_now(self) -> DesignValue:
        """The criterion of the campaign as it is."""
        return self.value(np.zeros(len(self.candidates), dtype=int))

    def sigma_quantile(self, q: float) -> float:
        """σ_model at level ``q`` by interpolation of the nodes, mm."""
        return float(np.interp(q, NODE_LEVELS, self.nodes))


__all__ = ["DesignProblem", "DesignValue", "sigma_nodes", "current_posterior", "prior_means", "MAX_INSTANCES",
           "NODE_LEVELS", "PROMISE"]
