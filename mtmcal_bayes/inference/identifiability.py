"""What a campaign determines, computed from its Jacobian (SPEC §19: identifiability is computed, not written down).

The measurements ``y ≈ J θ`` (``θ``: deviations and nuisance terms) determine a combination ``cᵀθ_dev`` of the
deviations exactly when ``(c, 0)`` lies in the row space of the FULL ``J`` — nuisance columns included, so a
deviation confounded with a set-up term (the spindle offset along its axis with the tool-length error) is not
determined however many repeats are taken.  Equivalently, ``c`` is orthogonal to the deviation part of every null
vector of ``J``.  With ``S`` the span of those deviation parts (``N_dev``):

* deviation ``i`` is *determined* when ``e_i ⟂ S``;
* *undetermined* when ``e_i ∈ S``: it enters no estimable combination; the data say nothing of it, its posterior
  is its prior (narrowed only by the priors of the nuisance terms it is confounded with);
* otherwise it is determined only in *combination*.  The orthogonal projection onto ``S`` is block diagonal over
  the connected components of its sparsity pattern (the finest split of ``S`` into pieces on disjoint sets of
  deviations); the estimable combinations supported on a block are the vectors on the block orthogonal to ``S``,
  stated in reduced row echelon form (sparse, leading weight 1).

Nothing here knows a machine: the names come from the parameter space.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.sparse.csgraph import connected_components

from .. import units
from ..errors import ParameterError
from ..parameters import weights as quantity_weights
from .analytic import linearisation

#: a unit vector whose component in (or out of) a subspace is below this is taken as orthogonal to (or in) it;
#: also the relative size below which a weight is dropped.  The null basis carries the Jacobian's relative error
#: over the smallest kept singular value: central differences (~1e-10) over ~1e-2 on the thesis campaign give
#: entries of ~3e-10, too close to 1e-9 to cut there; a real weight of 1e-6 relative changes no stated digit.
SUBSPACE_TOL = 1e-6
#: significant digits of the weights written into a combination's name
NAME_DIGITS = 4


#: what the data say of a quantity (:meth:`Identifiability.of`); the words are those of the summaries' JSON
#: ``identification`` key, which scripts read
DETERMINED, IN_COMBINATION, UNDETERMINED = "data", "combination", "not identified"


@dataclass(frozen=True)
class Combination:
    """An estimable combination ``Σ w·θ`` of deviations, in display units (µm, ″).

    ``name`` reads like ``"dx_CZ − dx_BT"`` or ``"dy_CZ + 1.728 µm/″·alpha_BT"`` (weights to 4 significant digits,
    with the unit ratio where the kinds differ); ``weights`` (deviation -> weight, the leading one first and 1);
    ``unit`` the display unit of the leading deviation, which is the unit of the combination.
    """

    name: str
    weights: dict[str, float]
    unit: str


@dataclass(frozen=True)
class Identifiability:
    """Which deviations a campaign determines: one by one, only in combination, or not at all."""

    determined: tuple[str, ...]
    combinations: tuple[Combination, ...]
    undetermined: tuple[str, ...]
    #: the classified deviations, and an orthonormal basis ``(d, r)`` (display units) of the directions of them the
    #: data do not see (:meth:`estimable`)
    deviations: tuple[str, ...] = field(default=(), compare=False)
    unseen: np.ndarray | None = field(default=None, compare=False, repr=False)

    def estimable(self, weights: dict[str, float], tol: float = 1e-6) -> bool:
        """Whether the data determine ``Σ w·θ`` (``weights`` per display unit; deviations not classified, e.g. held
        at zero, count as known): it has no part along a direction the data do not see."""
        c = np.array([weights.get(n, 0.0) for n in self.deviations])
        norm = float(np.linalg.norm(c))
        if norm == 0.0 or self.unseen is None or self.unseen.shape[1] == 0:
            return True
        return float(np.linalg.norm(self.unseen.T @ c)) <= tol * norm

    def of(self, name: str, weights: dict[str, float] | None = None) -> tuple[str | None, tuple[str, ...]]:
        """What the data say of the quantity ``name`` (a deviation, or a derived quantity such as
        ``dx_CZ_minus_dx_BT``; ``weights`` per display unit, default :func:`~mtmcal_bayes.parameters.weights`):
        ``(verdict, combinations)``.

        ``verdict`` is :data:`DETERMINED` when the data determine it (:meth:`estimable`), else
        :data:`IN_COMBINATION` when it enters an estimable combination (``combinations``: their names), else
        :data:`UNDETERMINED`; None for a quantity on no classified deviation (a discrepancy scale).
        """
        w = {n: v for n, v in (weights or quantity_weights(name)).items() if n in self.deviations and v}
        if not w:
            return None, ()
        if self.estimable(w):
            return DETERMINED, ()
        combos = tuple(c.name for c in self.combinations if set(c.weights) & set(w))
        return (IN_COMBINATION if combos else UNDETERMINED), combos

    def as_dict(self) -> dict:
        """JSON-ready: ``{"determined": [...], "combinations": [{"name", "weights", "unit"}],
        "undetermined": [...]}``."""
        return {"determined": list(self.determined),
                "combinations": [{"name": c.name, "weights": dict(c.weights), "unit": c.unit}
                                 for c in self.combinations],
                "undetermined": list(self.undetermined)}


def identifiability(jac, space, *, deviations=None, rtol: float = 1e-7, known=()) -> Identifiability:
    """Classify the deviations of ``space`` by what the measurements with Jacobian ``jac`` determine.

    Parameters
    ----------
    jac:
        ``(m, p)``, d(prediction)/d(parameter) in internal units (mm per mm, mm per rad), columns in the order
        of ``space.names``; e.g. :func:`mtmcal_bayes.models.jacobian` of a model.
    space:
        The :class:`~mtmcal_bayes.parameters.ParameterSpace` of the columns; parameters of group ``"deviation"``
        are classified, all others are nuisance terms, free: the data must explain them too.
    deviations:
        Names of the deviations to classify (default every deviation column).  The others stay free parameters,
        like nuisance terms; to hold a deviation at zero, put it in ``known`` (or leave it out of the space).
    rtol:
        Singular values below ``rtol · s_max`` of the Jacobian (columns in µm and ″) count as zero.  A central
        difference Jacobian of a nonlinear model shows its exact null directions near 1e-10 relative (rounding
        of ~400 mm positions over 1 µm / 1″ steps, and the steps' third-order term); a weak but real direction
        of a calibration is 1e-3 or above (1e-2 on the thesis campaign).  1e-7 lies three decades from each.
    known:
        Parameters the set-up fixes rather than the data (held at their nominal, their columns left out), as full
        names (``"xT[RB1]"``) or base names (``"xT"``: every owner).  The thesis' identification rests on the
        T ball being centred before the runs (``known=("xT", "yT", "zT")``); with them free, the T-ball offset of
        each tool setup absorbs what that setup's runs say about the spindle side.

    Returns
    -------
    :class:`Identifiability`, names in the space's order; within a combination the deviation listed last in the
    space leads (in the thesis' Table 2.1 order, the workpiece side: ``dx_CZ − dx_BT``, the C axis relative to
    the spindle).
    """
    jac = np.asarray(jac, dtype=float)
    if jac.ndim != 2 or jac.shape[1] != len(space):
        raise ParameterError("jac", f"shape {jac.shape} does not match the {len(space)} parameters of the space")
    params = space.parameters
    unknown = sorted(set(known) - {p.name for p in params} - {p.base for p in params})
    if unknown:
        raise ParameterError("known", f"not parameters of the space: {', '.join(unknown)}")
    free = [i for i, p in enumerate(params) if p.name not in set(known) and p.base not in set(known)]
    free_dev = [p.name for p in (params[i] for i in free) if p.group == "deviation"]
    if deviations is not None:
        unknown = sorted(set(deviations) - {p.name for p in params if p.group == "deviation"})
        if unknown:
            raise ParameterError("deviations", f"not deviations of the space: {', '.join(unknown)}")
        free_dev = [d for d in free_dev if d in set(deviations)]
    names = [params[i].name for i in free]
    rows = [names.index(d) for d in free_dev]         # the classified deviations among the free columns
    if not rows:
        return Identifiability((), (), ())

    a = (jac * space.display_scale())[:, free]        # per µm and per ″: columns on one footing
    _, s, vt = np.linalg.svd(a, full_matrices=True)
    rank = int(np.sum(s > rtol * s[0])) if s.size and s[0] > 0 else 0
    return classify(vt[rank:].T[rows], free_dev, space)   # deviation rows of a null basis of the full J


def classify(null_dev: np.ndarray, deviations: list[str], space) -> Identifiability:
    """Classify ``deviations`` given ``null_dev`` ``(d, k)``: the deviation parts (display units) of the directions
    the data leave undetermined."""
    if not deviations:
        return Identifiability((), (), (), (), np.zeros((0, 0)))
    u, sd, _ = np.linalg.svd(null_dev, full_matrices=False)
    basis = u[:, sd > SUBSPACE_TOL]                   # (d, r): orthonormal basis of S
    proj = basis @ basis.T                            # (d, d): projection onto S, whatever the basis

    link = np.abs(proj) > SUBSPACE_TOL
    np.fill_diagonal(link, False)
    _, label = connected_components(link, directed=False)

    determined, undetermined, combinations = [], [], []
    for b in dict.fromkeys(label):                    # blocks in the order of their first deviation
        members = np.flatnonzero(label == b)
        estimable = _complement(basis[members])       # (b, e): combinations on the block orthogonal to S
        block_names = [deviations[i] for i in members]
        if estimable.shape[1] == 0:
            undetermined += block_names
        elif len(members) == 1:
            determined += block_names
        else:
            combinations += _combinations(estimable, block_names, space)
    return Identifiability(tuple(determined), tuple(combinations), tuple(undetermined), tuple(deviations), basis)


def _complement(rows: np.ndarray) -> np.ndarray:
    """Orthonormal basis ``(b, e)`` of the vectors orthogonal to the columns of ``rows`` ``(b, r)``."""
    u, s, _ = np.linalg.svd(rows, full_matrices=True)
    r = int(np.sum(s > SUBSPACE_TOL))
    return u[:, r:]


def _combinations(estimable: np.ndarray, block_names: list[str], space) -> list[Combination]:
    """The combinations spanned by the columns of ``estimable`` ``(b, e)`` (display units) in reduced row echelon
    form, pivots taken from the last deviation of the block backwards."""
    rref = estimable.T[:, ::-1].copy()                # rows: combinations; columns: last deviation first
    order = block_names[::-1]
    pivots, row = [], 0
    for col in range(rref.shape[1]):
        if row == rref.shape[0]:
            break
        best = row + int(np.argmax(np.abs(rref[row:, col])))
        if abs(rref[best, col]) <= SUBSPACE_TOL:
            continue
        rref[[row, best]] = rref[[best, row]]
        rref[row] /= rref[row, col]
        for other in range(rref.shape[0]):
            if other != row:
                rref[other] -= rref[other, col] * rref[row]
        pivots.append(col)
        row += 1
    out = []
    for r, col in enumerate(pivots):
        w = rref[r]
        keep = [j for j in [col] + [j for j in range(len(order)) if j != col]
                if abs(w[j]) > SUBSPACE_TOL * np.abs(w).max()]
        weights = {order[j]: 1.0 if j == col else float(w[j]) for j in keep}
        out.append(_named(weights, space))
    return out


def _named(weights: dict[str, float], space) -> Combination:
    """A :class:`Combination` of ``weights`` (leading deviation first, weight 1) with its readable name."""
    unit_of = {p.name: p.unit for p in space.parameters}
    lead, *rest = weights
    text = lead
    for n in rest:
        w = weights[n]
        ratio = "" if unit_of[n] == unit_of[lead] else f" {units.SYMBOL[unit_of[lead]]}/{units.SYMBOL[unit_of[n]]}"
        magnitude = f"{abs(w):.{NAME_DIGITS}g}"
        factor = "" if magnitude == "1" and not ratio else f"{magnitude}{ratio}·"
        text += f" {'−' if w < 0 else '+'} {factor}{n}"
    return Combination(text, weights, unit_of[lead])



# ---------------------------------------------------------------- of a campaign's posterior
#: nuisance terms the set-up fixes: the T ball is centred before the runs (thesis Sec 4.2.2)
CENTRED = ("xT", "yT", "zT")


def campaign_identifiability(post) -> Identifiability:
    """What the campaign and data of the log posterior ``post`` determine: :func:`identifiability` of its forward
    model's Jacobian at zero (the ``linear`` model's design itself), the T ball taken as centred (:data:`CENTRED`), as
    the thesis does."""
    space = post.space
    known = [b for b in CENTRED if any(p.base == b for p in space.parameters)]
    return identifiability(linearisation(post)[0], space, known=known)
