"""Which quantities a design's runs determine: the Jacobian rule of :mod:`mtmcal_bayes.inference.identifiability`
on the planner's own rows (SPEC §20: one meaning of "determined").

A quantity ``cᵀθ`` (a target's row of the planner's ``T``) is determined by the campaign's runs plus a set of
candidate runs exactly when ``c`` is orthogonal to every null vector of their stacked rows, nuisance columns
included (free) and the T ball centred (:data:`~mtmcal_bayes.inference.identifiability.CENTRED`, as the report and
``axes`` take it).  The design search asks this of many sets of candidates: with ``Z`` an orthonormal basis of the
null space of a set's rows, one more run with rows ``R`` leaves the null space ``Z·null(R Z)``, so every candidate
added to a design is one small batched SVD.  A second run of a candidate adds no deviation row beyond its first's
(it differs only by its own W-ball offsets), so a design's support (the candidates run at least once) decides.
"""

from __future__ import annotations

import numpy as np

from ..inference.identifiability import CENTRED, SUBSPACE_TOL, identifiability

#: singular values below this fraction of the largest of all rows (campaign plus every candidate) count as zero:
#: the rule of :func:`~mtmcal_bayes.inference.identifiability.identifiability` (its ``rtol``)
RTOL = 1e-7
#: a candidate's rows of singular values below this fraction of the rule's tolerance are dropped (they decide no rank)
FAR_BELOW = 1e-3


class Determination:
    """What the campaign's rows plus any set of candidates determine of the planner's targets.

    Parameters
    ----------
    planner : :class:`.design.Planner` (its space, its campaign rows ``A`` (m, P) and target matrix ``T`` (t, P))
    rows : the candidates' rows ``[(k_i, P), ...]`` (:meth:`.design.Planner.candidate_rows`, weights dropped)
    """

    def __init__(self, planner, rows: list[np.ndarray]):
        self.planner = planner
        space = planner.space
        known = {b for b in CENTRED if any(p.base == b for p in space.parameters)}
        self.free = np.array([i for i, p in enumerate(space.parameters) if p.base not in known and p.name not in known],
                             dtype=int)
        scale = space.display_scale()[self.free]  # per µm and per ″: columns on one footing
        self.J0 = planner.A[:, self.free] * scale
        own = [A[:, self.free] * scale for A in rows]
        self.rows = rows
        allrows = np.vstack([self.J0] + own)
        s = np.linalg.svd(allrows, compute_uv=False) if allrows.size else np.zeros(0)
        self.tol = RTOL * (s[0] if s.size and s[0] > 0 else 1.0)
        # each candidate's rows as S·Vᵀ (its SVD: the same singular values times any basis Z, so the same null
        # spaces) without the rows of singular values far below the rule's (FAR_BELOW of it: the rank decisions at
        # the tolerance are the same), and the candidates in groups of their row counts: a probe's or an R-test's
        # hundreds of rows, padded for all, made every candidate's SVD as large as theirs
        own = [_as_few_rows(A, self.tol * FAR_BELOW) for A in own]
        r_max = max((len(A) for A in own), default=1)
        self.R = np.zeros((len(rows), r_max, len(self.free)))
        for k, A in enumerate(own):
            self.R[k, :len(A)] = A
        sizes = np.array([max(len(A), 1) for A in own], dtype=int)
        self._groups = [(np.flatnonzero(sizes == r), int(r)) for r in np.unique(sizes)]
        C = planner.T[:, self.free] * scale  # (t, F) display units: what each target weighs
        norm = np.linalg.norm(C, axis=1, keepdims=True)
        self.C = C / np.where(norm > 0, norm, 1.0)
        self._null: dict[bytes, np.ndarray] = {}
        self._plus_one: dict[bytes, np.ndarray] = {}

    def _null_of(self, support: np.ndarray) -> np.ndarray:
        """Orthonormal basis ``(F, k)`` of the null space of the campaign's rows and the rows of ``support`` (K,)."""
        key = np.asarray(support, dtype=bool).tobytes()
        if key not in self._null:
            J = np.vstack([self.J0] + [self.R[k] for k in np.flatnonzero(support)])
            if not len(J):
                self._null[key] = np.eye(len(self.free))
            else:
                # vt in full (its last rows span the null space), U only as wide as needed: a probe's or an
                # R-test's rows are hundreds, and U in full would be their square
                _, s, vt = np.linalg.svd(J, full_matrices=len(J) < J.shape[1])
                self._null[key] = vt[int(np.sum(s > self.tol)):].T
        return self._null[key]

    def unseen(self, counts=None) -> np.ndarray:
        """(t,) the part of each (unit) target the campaign plus the candidates with ``counts`` > 0 (None: the
        campaign alone) do not see: the norm of its projection onto their rows' null space, 0 … 1."""
        counts = np.zeros(len(self.R), dtype=int) if counts is None else np.asarray(counts)
        Z = self._null_of(counts > 0)
        return np.linalg.norm(self.C @ Z, axis=1)

    def determined(self, counts=None) -> np.ndarray:
        """(t,) whether each target is determined by the campaign plus the candidates with ``counts`` > 0 (None:
        the campaign alone)."""
        return self.unseen(counts) <= SUBSPACE_TOL

    def unseen_many(self, counts: np.ndarray) -> np.ndarray:
        """(B, t) :meth:`unseen` of designs ``counts`` (B, K)."""
        return np.stack([self.unseen(c) for c in np.atleast_2d(counts)])

    def unseen_plus_one(self, counts: np.ndarray) -> np.ndarray:
        """(K, t) :meth:`unseen` after one more run of each candidate ``k`` added to ``counts`` (K,); a design's
        support decides it, so it is made once per support (the search asks it again and again)."""
        counts = np.asarray(counts)
        key = (counts > 0).tobytes()
        if key not in self._plus_one:
            self._plus_one[key] = self._unseen_plus_one(counts)
        return self._plus_one[key]

    def _unseen_plus_one(self, counts: np.ndarray) -> np.ndarray:
        Z = self._null_of(counts > 0)
        K, t = len(self.R), len(self.C)
        if Z.shape[1] == 0:
            return np.zeros((K, t))
        g = self.C @ Z  # (t, kz): the targets in the null space's basis
        after = np.empty((K, t))
        for idx, r in self._groups:
            B = self.R[idx, :r] @ Z  # (k, r, kz)
            _, s, vt = np.linalg.svd(B, full_matrices=False)  # vt (k, min(r, kz), kz)
            seen = np.arange(vt.shape[1])[None, :] < np.sum(s > self.tol, axis=1)[:, None]  # rows spanning B's rows
            G = np.einsum("tz,kjz->ktj", g, vt)  # (k, t, ·): the targets along each direction B sees
            # what is left unseen: the part of each target outside B's row space
            after[idx] = np.sqrt(np.maximum(np.sum(g**2, axis=1)[None]
                                            - np.sum(np.where(seen[:, None, :], G, 0.0) ** 2, axis=2), 0.0))
        return np.where(counts[:, None] > 0, self.unseen(counts)[None, :], after)  # a further run adds nothing

    def determined_plus_one(self, counts: np.ndarray) -> np.ndarray:
        """(K, t): whether each target is determined after one more run of each candidate ``k``."""
        return self.unseen_plus_one(counts) <= SUBSPACE_TOL

    def identifiability(self, counts=None):
        """:class:`~mtmcal_bayes.inference.identifiability.Identifiability` of the campaign plus the candidates with
        ``counts`` > 0 (None: every candidate): which deviations, which combinations, which not at all."""
        support = np.ones(len(self.R), bool) if counts is None else np.asarray(counts) > 0
        rows = [self.planner.A] + [self.rows[k] for k in np.flatnonzero(support)]
        space = self.planner.space
        known = [b for b in CENTRED if any(p.base == b for p in space.parameters)]
        return identifiability(np.vstack(rows), space, known=known)


def _as_few_rows(R: np.ndarray, below: float) -> np.ndarray:
    """``R`` (r, F) as ``S·Vᵀ`` (at most min(r, F) rows) without the rows of singular values at or below ``below``."""
    _, s, vt = np.linalg.svd(R, full_matrices=False)
    keep = s > below
    return s[keep, None] * vt[keep]


def single_deviation(planner) -> list[str | None]:
    """Per target, the deviation it is (its row of ``T`` one deviation's), else None (a combination)."""
    names = planner.space.names
    out = []
    for row in planner.T:
        nz = np.flatnonzero(row)
        out.append(names[nz[0]] if len(nz) == 1 else None)
    return out


def why_left_out(ident, deviation: str) -> str:
    """Why ``deviation`` is no target of its own, by what every candidate run with the campaign's determines."""
    for c in ident.combinations:
        if deviation in c.weights:
            return f"determined only in the combination {c.name}"
    if deviation in ident.undetermined:
        return "no candidate run determines it (its posterior would be its prior)"
    return "determined, but not among the machine's default quantities"


def not_targeted(planner, ident) -> dict[str, str]:
    """{deviation: why} of the planner's deviations that are no target of their own (:func:`why_left_out`)."""
    singles = set(single_deviation(planner))
    devs = [p.name for p in planner.space.parameters if p.group == "deviation"]
    return {d: why_left_out(ident, d) for d in devs if d not in singles}


__all__ = ["SUBSPACE_TOL", "Determination", "not_targeted", "single_deviation", "why_left_out"]
