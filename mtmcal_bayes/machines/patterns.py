"""Ball-bar patterns and nominal kinematics of a described machine (SPEC §19, generalising thesis Sec 2.3).

A pattern ``<K><d>`` swivels rotary axis K over an arc while the linear axes interpolate so that, nominally,
the tool-side (T) ball stays ``L_B`` from the workpiece-side (W) ball along the bar direction ``u``; the other
rotary axes are held (``hold``, default 0).  ``d`` is the bar's sensitive direction:

* ``R`` radial: ``T − W = −L_B·r̂``, r̂ the outward radial from K's line through the ball on K's side (the T
  ball for an axis carrying the tool, the W ball for one carrying the workpiece; a ball on K's line: r̂ along
  the frame axis of the pattern's first component at the home pose, +X for a C axis, as the thesis' CR at
  R_C = 0); on the thesis machine BR and CR (Table 2.3's geometry, T inside W);
* ``T`` tangential: ``T − W = L_B·(k × r̂)``, along the way that ball moves as K turns positively (CT; the
  thesis' BT is this bar reversed, below);
* ``A`` axial: ``T − W = L_B·k`` (BA, CA);
* ``X``, ``Y``, ``Z``: along the machine axis, fixed while K turns (BX, CY, ...).

A run may have its bar *reversed*, the T ball on the other side of the W ball: ``u`` turned (for R the T ball
outside, for T trailing: the thesis' BT, and its CR in the geometry of its Fig 2.6).

``u`` turns with K and the axes below it (for R, T, A).  The W ball is placed at the mount's ``position``
(at the home pose, on the workpiece side) the thesis way: where the actual tool ball (the dummy sphere) is
at the home rotary pose and the linear commands that nominally bring it there.

Eccentricities are read as the thesis reads them, ``dL = r0 + e_1 cos ψ + e_2 sin ψ``, in the plane
perpendicular to K's frame axis k at the home pose, the components along the next frame axes in cyclic order
(k = Z: ``ex, ey``; k = Y: ``ez, ex``; k = X: ``ey, ez``: the thesis' B and C patterns); ψ is the commanded
angle of K, or for R patterns the polar angle of ``u`` in that plane (the thesis' CR: θ + 180°).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .description import FRAME, Axis, MachineDescription

#: sensitive directions of a pattern: cylindrical about K, then the machine axes
DIRECTIONS = ("R", "T", "A", "X", "Y", "Z")
#: default arc of an axis with less than a full turn of travel, degrees (the thesis' B range)
PARTIAL_ARC_DEG = 90.0
#: angle steps of the default grids, degrees (the thesis' 1° over an arc, 5° over a turn)
ARC_STEP_DEG, TURN_STEP_DEG = 1.0, 5.0


def turn(v: np.ndarray, ax: Axis, angle, *, about_origin: bool = False) -> np.ndarray:
    """``v`` (..., k, 3) turned by ``angle`` (k,) rad about rotary axis ``ax``'s nominal line (through the origin
    instead: a direction); an inclined axis by Rodrigues' formula about its direction."""
    if ax.inclined:
        return _rodrigues(v, ax.direction, np.zeros(3) if about_origin else ax.point, angle)
    axis, point = ax.frame_axis, np.zeros(3) if about_origin else ax.point
    j, m = (axis + 1) % 3, (axis + 2) % 3
    c, s = np.cos(angle), ax.sign * np.sin(angle)
    out = np.array(v, copy=True)  # complex where a complex-step derivative goes through
    vj, vm = v[..., j] - point[j], v[..., m] - point[m]
    out[..., j] = c * vj - s * vm + point[j]
    out[..., m] = s * vj + c * vm + point[m]
    return out


def _rodrigues(v: np.ndarray, k: np.ndarray, point: np.ndarray, angle) -> np.ndarray:
    """``v`` (..., k, 3) turned by ``angle`` (k,) rad right-handedly about the line through ``point`` (3,) along the
    unit vector ``k`` (3,): ``p + r cos θ + (k × r) sin θ + k (k·r)(1 − cos θ)``, r = v − p."""
    c, s = np.cos(angle)[..., None], np.sin(angle)[..., None]
    r = np.asarray(v) - point
    along = (r @ k)[..., None] * k
    return point + c * r + s * np.cross(k, r) + (1.0 - c) * along


def components(desc: MachineDescription, pattern: str) -> tuple[str, str]:
    """The eccentricity components of ``pattern`` (``"CR"`` -> ``("ex", "ey")``)."""
    k = axis_of(desc, pattern).frame_axis
    return f"e{FRAME[(k + 1) % 3].lower()}", f"e{FRAME[(k + 2) % 3].lower()}"


def axis_of(desc: MachineDescription, pattern: str) -> Axis:
    """The rotary axis a pattern swivels; ValueError for a pattern this machine does not have."""
    if len(pattern) != 2 or pattern[1] not in DIRECTIONS:
        raise ValueError(f"{pattern!r} is not a pattern (expected <axis><direction>, direction one of "
                         f"{', '.join(DIRECTIONS)}, e.g. {desc.rotary_axes[0].letter}R)")
    ax = desc.axes.get(pattern[0])
    if ax is None or not ax.rotary:
        raise ValueError(f"{pattern!r}: {pattern[0]} is not a rotary axis of this machine "
                         f"({', '.join(a.letter for a in desc.rotary_axes)})")
    return ax


def patterns_of(desc: MachineDescription) -> list[str]:
    """Every pattern of the machine: each rotary axis with each direction."""
    return [a.letter + d for a in desc.rotary_axes for d in DIRECTIONS]


def default_arc_deg(ax: Axis) -> np.ndarray:
    """The default angle grid of axis ``ax``, degrees: a turn by 5° if it turns fully (or no travel is given),
    else 90° by 1° from 0 (from the travel's end where 0–90° does not fit)."""
    if ax.travel is None or np.rad2deg(ax.travel[1] - ax.travel[0]) >= 360.0:
        return np.arange(0.0, 360.0, TURN_STEP_DEG)
    lo, hi = np.rad2deg(ax.travel)
    start = min(max(lo, 0.0), hi)
    end = min(start + PARTIAL_ARC_DEG, hi)
    if end - start < PARTIAL_ARC_DEG:
        start = max(lo, end - PARTIAL_ARC_DEG)
    return np.arange(start, end + 1e-9, ARC_STEP_DEG)


def side_of(desc: MachineDescription, ax: Axis) -> tuple[Axis, ...]:
    return desc.work_chain if ax.work_side else desc.tool_chain


def nominal_down(v: np.ndarray, chain, q: dict[str, np.ndarray], *, above: Axis | None = None,
                 directions: bool = False) -> np.ndarray:
    """``v`` (k, 3) taken down the rotary axes of ``chain`` (bed outwards) at commands ``q``; only the axes
    from ``above`` down (inclusive) if given; ``directions``: turn vectors (no axis points)."""
    axes = list(chain)
    if above is not None:
        axes = axes[: axes.index(above) + 1]
    for ax in reversed(axes):
        if ax.rotary:
            v = turn(v, ax, q[ax.letter], about_origin=directions)
    return v


def tool_home(desc: MachineDescription, length: float) -> np.ndarray:
    """The tool point (3,) at the home pose for a programmed length ``length`` mm."""
    return desc.spindle.point + length * desc.spindle.direction


@dataclass(frozen=True)
class PatternCommands:
    """Commands of one pattern over its grid: ``q`` {letter: (k,)} (mm, rad), ``psi`` (k,) rad, ``angle_deg`` (k,)."""

    q: dict
    psi: np.ndarray
    angle_deg: np.ndarray


def linear_commands(desc: MachineDescription, q_rot: dict, tool: np.ndarray, target_rel: np.ndarray) -> dict:
    """Linear commands (k,) each bringing the nominal tool point to ``target_rel`` (k, 3) relative to the
    workpiece-side point's rotary part, i.e. ``Σ q_L e_L = target_rel − t_rot(q)``."""
    k = len(next(iter(q_rot.values())))
    t_rot = nominal_down(np.broadcast_to(tool, (k, 3)), desc.tool_chain, q_rot)
    need = target_rel - t_rot
    return {a: need[:, FRAME.index(a)] for a in FRAME}


def centre_commands(desc: MachineDescription, q_rot: dict, *, tool: np.ndarray, point: np.ndarray) -> dict:
    """Linear commands {X, Y, Z: (k,)} mm that put the nominal tool point ``tool`` ((3,) or (k, 3), home pose, tool
    side) on the nominal workpiece point ``point`` ((3,) or (k, 3), home pose) at rotary commands ``q_rot``
    {letter: (k,)} rad: the nominal inverse chain, exact (the linear axes sit below every rotary axis), as the
    R-test's run and its program command them."""
    k = len(next(iter(q_rot.values())))
    w_rot = nominal_down(np.broadcast_to(point, (k, 3)), desc.work_chain, q_rot)
    return linear_commands(desc, q_rot, tool, w_rot)


def pattern_commands(desc: MachineDescription, pattern: str, *, length: float, ball: np.ndarray, bar: float,
                     arc_deg=None, hold_deg: dict | None = None, reverse: bool = False) -> PatternCommands:
    """Nominal commands of ``pattern`` for a tool of programmed ``length`` (mm), the W ball at ``ball`` (3,) (home
    pose, workpiece side), bar length ``bar`` (mm), over ``arc_deg`` (default :func:`default_arc_deg`) with the
    other rotary axes at ``hold_deg`` (degrees, default 0); ``reverse``: the T ball on the other side of the W
    ball (the bar direction ``u`` turned: outside for R, trailing for T, ``−k`` for A, the negative axis for X, Y,
    Z)."""
    ax = axis_of(desc, pattern)
    d = pattern[1]
    theta_deg = default_arc_deg(ax) if arc_deg is None else np.asarray(arc_deg, dtype=float)
    theta = np.deg2rad(theta_deg)
    k = len(theta)
    q = {a.letter: np.full(k, np.deg2rad((hold_deg or {}).get(a.letter, 0.0))) for a in desc.rotary_axes}
    q[ax.letter] = theta
    tool = tool_home(desc, length)
    w = nominal_down(np.broadcast_to(ball, (k, 3)), desc.work_chain, q)
    side = side_of(desc, ax)
    kvec = ax.direction
    if d in "XYZ":
        u = np.zeros((k, 3))
        u[:, FRAME.index(d)] = 1.0
    else:
        if d == "A":
            u0 = kvec
        else:
            q0 = {a: (np.zeros(1) if a == ax.letter or _below(side, a, ax) else v[:1]) for a, v in q.items()}
            b = nominal_down(tool[None, :], desc.tool_chain, q0) if not ax.work_side else \
                nominal_down(np.asarray(ball, float)[None, :], desc.work_chain, q0)
            rel = b[0] - ax.point
            radial = rel - (rel @ kvec) * kvec
            norm = float(np.linalg.norm(radial))
            if norm < 1e-9:  # the ball on K's line: r̂ along the first component's frame axis at the home pose
                r_hat = np.zeros(3)
                r_hat[(ax.frame_axis + 1) % 3] = 1.0
                if ax.inclined:  # across K: its basis' u
                    r_hat = ax.basis[0]
            else:
                r_hat = radial / norm
            u0 = -r_hat if d == "R" else np.cross(kvec, r_hat)
        u = nominal_down(np.broadcast_to(u0, (k, 3)), side, q, above=ax, directions=True)
    if reverse:
        u = -u
    q.update(linear_commands(desc, q, tool, w + bar * u))
    if d == "R":
        kf = ax.frame_axis
        psi = np.arctan2(u[:, (kf + 2) % 3], u[:, (kf + 1) % 3])
        psi = np.unwrap(psi)
    else:
        psi = theta.copy()
    return PatternCommands(q, psi, theta_deg)


def _below(side, letter: str, ax: Axis) -> bool:
    """Whether axis ``letter`` is on ``side`` below ``ax`` (nearer the bed)."""
    letters = [a.letter for a in side]
    return letter in letters and letters.index(letter) < letters.index(ax.letter)


def ball_radius(desc: MachineDescription, ax: Axis, ball: np.ndarray, hold_deg: dict | None = None) -> float:
    """Distance, mm, of a W ball at ``ball`` (3,) (home pose, workpiece side) from the line of the workpiece-side axis
    ``ax``, the axes it carries at ``hold_deg`` (degrees, default 0): the radius ``ax``'s patterns swivel the ball
    on (below 1e-9 the ball is on the line, where :func:`pattern_commands` takes r̂ by convention)."""
    q = {a.letter: np.full(1, 0.0 if a.letter == ax.letter or _below(desc.work_chain, a.letter, ax)
                           else np.deg2rad((hold_deg or {}).get(a.letter, 0.0))) for a in desc.rotary_axes}
    rel = nominal_down(np.asarray(ball, float)[None, :], desc.work_chain, q)[0] - ax.point
    return float(np.linalg.norm(rel - (rel @ ax.direction) * ax.direction))


def placement_commands(desc: MachineDescription, *, length: float, ball: np.ndarray) -> dict:
    """Commands (each (1,)) of the pose at which a mount's W ball is placed on the dummy sphere: rotary axes at 0,
    the linear axes bringing the nominal tool point onto ``ball``."""
    q = {a.letter: np.zeros(1) for a in desc.rotary_axes}
    tool = tool_home(desc, length)
    q.update(linear_commands(desc, q, tool, np.asarray(ball, float)[None, :]))
    return q


def fit_basis(psi: np.ndarray) -> np.ndarray:
    """Design matrix ``(k, 3)`` of the eccentricity fit: ``1, cos ψ, sin ψ``."""
    return np.c_[np.ones_like(psi), np.cos(psi), np.sin(psi)]
