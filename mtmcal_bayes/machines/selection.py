"""The default selection of a machine's location errors, computed on every machine (SPEC §21).

An error is left out of the default set when its **column** lies in the span of the columns before it.  A column
is the derivative of the tool point relative to a workpiece-side point, ``T(q) − W(q)`` (µm per µm or per ″),
stacked over many random poses: random commands of every axis within its travel (a full turn, ±300 mm where none
is given), a random tool length per pose (50–350 mm from the spindle's ``point_mm`` along it) and a random
workpiece-side point per set-up of poses.  The derivatives are the chain's own (:class:`~.chain.Chain`), by the
complex step (exact to rounding), all columns in one batch.

In the span from the start stand the nuisance terms every instrument carries (:data:`SPAN`):

* the tool ball's (or stylus ball's, or R-test nest's) length along the spindle, 1 column: one constant offset
  along the spindle at every pose (the ball bar's ``dRB``, the stylus' ``dRS``, each from a tool setter);
* the workpiece-side point's own placement, 3 columns per point: a constant offset in the workpiece frame.  Every
  instrument has one (the ball bar's W ball, ``xW, yW, zW`` per mount, placed where the dummy sphere is; the
  probe's sphere, ``xP, yP, zP`` per run; the R-test's sphere), so a location error that only moves a point where
  its placement would is never told from it: the outermost workpiece-side axis' zero, a constant translation of the
  whole tool side on a machine whose workpiece side only translates.

The tool ball's offset across the spindle (2 columns, constant in the spindle frame) is computed too but not in the
span: the ball bar's T ball is centred before the runs, so what acts as that offset the ball bar determines (the
probe's stylus, free across the spindle, does not: its campaign's identifiability says so).

Order: the workpiece-side axes from the bed outwards, then the tool-side axes from the bed outwards, then the
spindle; per axis its positions, then its zero, then its orientations.  The rank test is a Gram–Schmidt QR in that
order: a column whose part outside the span so far is below :data:`TOLERANCE` of its norm is left out, with the
combination of the kept columns (and nuisance terms) that reproduces it.  The gap between dependent and independent
columns is many orders of magnitude (docs/machines.md gives it per built-in type).  The squareness of the linear
axes stays out of the default set (measured by other means) and out of the test.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .. import units
from .chain import Chain
from .description import SPINDLE, MachineDescription, inclined_basis
from .deviations import Deviation, generated

#: set-ups (random workpiece-side points) and random poses per set-up
SETUPS, POSES = 6, 40
#: the random poses' seed: the rule is deterministic
SEED = 21
#: a column whose part outside the span of those before it is below this fraction of its norm is left out; the
#: dependent columns sit at ~1e-15, the independent ones above ~1e-3 on the built-in types
TOLERANCE = 1e-8
#: range of the random tool lengths (mm from the spindle's point_mm) and of the workpiece-side points (mm)
LENGTHS_MM, POINTS_MM = (50.0, 350.0), 200.0
#: travel assumed for an axis that states none: a full turn, ±300 mm
DEFAULT_TRAVEL = {True: (-np.pi, np.pi), False: (-300.0, 300.0)}
SQUARENESS_WHY = "linear-axis squareness: measured by other means; held at zero unless selected"
#: the nuisance terms computed, in the order of their columns
NUISANCE = ("tool offset across the spindle", "tool length", "workpiece-side point's placement")
#: the nuisance terms in the span from the start: those every instrument carries.  The tool ball's offset across the
#: spindle is not among them: the ball bar's T ball is centred before the runs (thesis Sec 4.2.2; the package's
#: identifiability takes it as known, ``inference.identifiability.CENTRED``), so an error that acts as that offset
#: is one the ball bar determines even where the probe's stylus (free across the spindle) does not
SPAN = NUISANCE[1:]
NUISANCE_WORDS = {
    NUISANCE[0]: "the tool ball's own offset across the spindle",
    NUISANCE[1]: "the tool ball's own length error",
    NUISANCE[2]: "the workpiece-side point's own placement, the W ball's or the sphere's",
}


@dataclass(frozen=True)
class LeftOut:
    """One error the default set leaves out: ``weights`` {kept error: coefficient} (display units of the kept per
    display unit of this one) and the ``nuisance`` terms (of :data:`NUISANCE`) whose columns reproduce this one's;
    ``residual`` what is left of its column, relative to its norm; ``why`` in words."""

    name: str
    weights: dict[str, float]
    nuisance: tuple[str, ...]
    residual: float
    why: str


@dataclass(frozen=True)
class Selection:
    """The rule's result: the errors kept in the default set (generated order), those left out with why, and the
    relative residual of every tested error's column outside the span before it (kept: large; left out: ~0)."""

    kept: tuple[str, ...]
    left_out: dict[str, LeftOut]
    residuals: dict[str, float]

    def why(self) -> dict[str, str]:
        return {name: lo.why for name, lo in self.left_out.items()}


def rule_order(desc: MachineDescription) -> list[Deviation]:
    """The generated errors (squareness excluded) in the rule's order: work side, tool side (each from the bed
    outwards), spindle; per body its positions, its zero, its orientations."""
    bodies = [a.letter for a in desc.work_chain + desc.tool_chain if a.rotary] + [SPINDLE]
    errs = [d for d in generated(desc) if d.role != "squareness"]

    def rank(d: Deviation) -> tuple[int, int]:
        zero = d.role == "orientation" and d.body != SPINDLE and \
            abs(abs(float(d.vector @ desc.axes[d.body].direction)) - 1.0) < 1e-12
        return bodies.index(d.body), 0 if d.role == "position" else (1 if zero else 2)

    return sorted(errs, key=rank)  # stable: within a role, generated order


def _poses(desc: MachineDescription, rng: np.random.Generator):
    """Commands ``{letter: (k,)}``, tool points (k, 3) and workpiece-side points (k, 3) of k = SETUPS·POSES poses."""
    k = SETUPS * POSES
    q = {}
    for ax in desc.axes.values():
        lo, hi = ax.travel if ax.travel is not None else DEFAULT_TRAVEL[ax.rotary]
        q[ax.letter] = rng.uniform(lo, hi, k)
    s = desc.spindle
    tool = s.point + rng.uniform(*LENGTHS_MM, k)[:, None] * s.direction
    work = np.repeat(rng.uniform(-POINTS_MM, POINTS_MM, (SETUPS, 3)), POSES, axis=0)
    return q, tool, work


def columns(desc: MachineDescription, errs: list[Deviation]) -> tuple[np.ndarray, np.ndarray, list[str]]:
    """``(J (m, p), N (m, r), kinds (r,))``: the columns of ``errs`` (µm per display unit) and of the nuisance terms
    (µm per µm), m = 3·SETUPS·POSES rows (the three components of ``T − W`` at each pose), r = 3 + 3·SETUPS; ``kinds``
    names each nuisance column by :data:`NUISANCE`."""
    q, tool, work = _poses(desc, np.random.default_rng(SEED))
    p, k, h = len(errs), len(tool), 1e-20
    n = p + 6
    step = np.array([units.to_internal(1.0, "arcsec" if d.kind == "angle" else "um") for d in errs] +
                    [units.to_internal(1.0, "um")] * 6)
    dev = {d.name: np.where(np.arange(n) == i, 1j * h * step[i], 0.0) for i, d in enumerate(errs)}
    u, v = inclined_basis(desc.spindle.direction)
    t_dirs = np.stack([u, v, desc.spindle.direction])  # the spindle frame at the home pose
    t = np.broadcast_to(tool, (n, k, 3)).astype(complex)
    t[p:p + 3] += 1j * h * step[p:p + 3, None, None] * t_dirs[:, None, :]
    w = np.broadcast_to(work, (n, k, 3)).astype(complex)
    w[p + 3:] += 1j * h * step[p + 3:, None, None] * np.eye(3)[:, None, :]
    chain = Chain(desc, errs)
    diff = (chain.tool_point(t, q, dev) - chain.work_point(w, q, dev)).imag / (h * units.to_internal(1.0, "um"))
    cols = diff.reshape(n, 3 * k).T  # rows: pose-major, xyz within a pose
    setup = np.repeat(np.arange(SETUPS), 3 * POSES)
    place = [np.where(setup == g, cols[:, p + 3 + j], 0.0) for g in range(SETUPS) for j in range(3)]
    nuisance = np.column_stack([cols[:, p:p + 3]] + place)
    kinds = [NUISANCE[0]] * 2 + [NUISANCE[1]] + [NUISANCE[2]] * (3 * SETUPS)
    return cols[:, :p], nuisance, kinds


def _coefficient(a: float) -> float:
    """A coefficient as shown: an integer where it is one to 1e-9."""
    r = round(a)
    return float(r) if abs(a - r) < 1e-9 else a


def _unit(d: Deviation) -> str:
    return "″" if d.kind == "angle" else " µm"


def _words(d: Deviation, weights: dict[str, float], kinds: dict[str, Deviation], *, nuisance: tuple[str, ...],
           zero: bool) -> str:
    """``why`` of a left-out error: the combinations through which it acts, and what 1 unit of it moves the tool
    point as (the kept errors' amounts, the nuisance terms')."""
    if zero:
        return "does not move the tool point relative to the workpiece"
    parts = []
    if weights:
        def scaled(a: float, k: Deviation) -> str:
            per = "" if k.kind == d.kind else f" {_unit(k).strip()}/{_unit(d).strip()}"
            return f"{abs(a):.6g}{per}·" if abs(a) != 1.0 or per else ""
        combos = [f"{k} {'−' if a < 0 else '+'} {scaled(a, kinds[k])}{d.name}" for k, a in weights.items()]
        amounts = [f"{a:.6g}{_unit(kinds[k])} of {k}" for k, a in weights.items()]
        parts.append(f"acts only through {' and '.join(combos)}: 1{_unit(d)} of it acts as "
                     + " and ".join(amounts).replace("-", "−"))
    if nuisance:
        words = [NUISANCE_WORDS[x] for x in nuisance]
        what = words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]
        s = "s" if len(words) > 1 else ""
        parts.append(f"{'the rest as' if weights else 'the same as'} {what} (each set-up's nuisance term{s})")
    return "; ".join(parts)


def _compute(desc: MachineDescription) -> Selection:
    errs = rule_order(desc)
    by_name = {d.name: d for d in errs}
    J, N, kinds = columns(desc, errs)
    N, kinds = N[:, [k in SPAN for k in kinds]], [k for k in kinds if k in SPAN]
    U, S, _ = np.linalg.svd(N, full_matrices=False)
    Q = U[:, S > TOLERANCE * S[0]]  # an orthonormal basis of the nuisance terms' span
    kept_cols: list[int] = []
    residuals, left = {}, {}
    for i, d in enumerate(errs):
        c = J[:, i]
        norm = float(np.linalg.norm(c))
        r = c - Q @ (Q.T @ c)
        r = r - Q @ (Q.T @ r)  # twice is enough (Kahan–Parlett)
        rel = float(np.linalg.norm(r)) / norm if norm > 0.0 else 0.0
        residuals[d.name] = rel
        if rel > TOLERANCE:
            kept_cols.append(i)
            Q = np.column_stack([Q, r / np.linalg.norm(r)])
            continue
        weights, nuisance = {}, ()
        if norm > 0.0:
            A = np.column_stack([J[:, kept_cols], N])
            coef = np.linalg.lstsq(A, c, rcond=None)[0]
            a, b = coef[:len(kept_cols)], coef[len(kept_cols):]
            weights = {errs[j].name: _coefficient(float(x)) for j, x in zip(kept_cols, a)
                       if abs(x) * np.linalg.norm(J[:, j]) > 1e-6 * norm}
            nuisance = tuple(x for x in NUISANCE
                             if np.linalg.norm(N[:, [kk == x for kk in kinds]] @ b[[kk == x for kk in kinds]])
                             > 1e-6 * norm)
        left[d.name] = LeftOut(d.name, weights, nuisance, rel,
                              _words(d, weights, by_name, nuisance=nuisance, zero=norm == 0.0))
    for d in generated(desc):
        if d.role == "squareness":
            left[d.name] = LeftOut(d.name, {}, (), float("nan"), SQUARENESS_WHY)
    kept = tuple(d.name for d in generated(desc) if d.name not in left)
    return Selection(kept, {d.name: left[d.name] for d in generated(desc) if d.name in left}, residuals)


def _key(desc: MachineDescription) -> tuple:
    """What the rule depends on, hashable: the chain's geometry, travels and names."""
    axes = tuple((a.letter, a.rotary, a.work_side, tuple(a.direction), tuple(a.point), a.travel, a.force_inclined)
                 for a in desc.work_chain + desc.tool_chain)
    s = desc.spindle
    return (desc.configuration, axes, tuple(s.direction), tuple(s.point), s.carrier, desc.aliases, desc.squareness)


_CACHE: dict[tuple, Selection] = {}


def default_selection(desc: MachineDescription) -> Selection:
    """The rule's result for ``desc`` (computed once per geometry; whatever its ``deviations`` list says)."""
    key = _key(desc)
    if key not in _CACHE:
        _CACHE[key] = _compute(desc)
    return _CACHE[key]


def spectrum(desc: MachineDescription) -> np.ndarray:
    """The singular values of the nuisance and error columns together, each column scaled to unit norm, largest
    first: as many are ~1e-15 as the rule leaves errors out (the gap the tolerance sits in)."""
    errs = rule_order(desc)
    J, N, kinds = columns(desc, errs)
    M = np.column_stack([N[:, [k in SPAN for k in kinds]], J])
    norms = np.linalg.norm(M, axis=0)
    return np.linalg.svd(M[:, norms > 0] / norms[norms > 0], compute_uv=False)


def redundant(desc: MachineDescription) -> dict[str, str]:
    """Generated errors left out of the default set, with why (SPEC §21, the rule above): each whose column lies
    in the span of the nuisance terms and the errors before it, named with the combination it acts through; and
    the squareness of the linear axes (held at zero, as in the thesis: measured by other means)."""
    return default_selection(desc).why()


def selected(desc: MachineDescription) -> list[Deviation]:
    """The deviations a campaign on this machine estimates: ``[machine] deviations`` if given (any generated error,
    those the rule leaves out included), else the generated ones less :func:`redundant`."""
    every = generated(desc)
    if desc.deviations is not None:
        chosen = set(desc.deviations)
        return [d for d in every if d.name in chosen or d.symbol in chosen]
    skip = redundant(desc)
    return [d for d in every if d.name not in skip]
