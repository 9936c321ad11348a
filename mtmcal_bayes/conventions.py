"""What a ball-bar centre offset means in machine axes: the reading convention of a run (SPEC §17).

A centre offset is a number only together with the frame it is read in.  The package's **machine frame**
(the frame its models predict in, SPEC §3) fixes, for every pattern, the direction each sample of the
trace stands for: ``ΔL(angle) = r0 + e_a·u_a(angle) + e_b·u_b(angle)`` with

* B patterns (B swivelling 0–90°, X and Z interpolating): ``(u_a, u_b) = (sin φ, cos φ)`` for
  ``(ex, ez)``, φ the B angle: the sample at B = 0° stands for +Z, the one at B = 90° for +X — where the
  programmed B-axis centre is, seen from the T ball it swings about;
* C patterns (C turning, X and Y interpolating): ``(u_a, u_b) = (cos ψ, sin ψ)`` for ``(ex, ey)``,
  ψ = θ (the C angle: the sample at C = 0° stands for +X, at C = 90° for +Y — where the balls are on the
  table), except CR in the thesis' geometry (T ball at radius R_C − L_B < 0), ψ = θ + 180°: the direction
  of the bar from the W ball to the T ball;
* ΔL positive when the bar extends, the bar lying as the commands of thesis Tables 2.2/2.3 put it (the T
  ball at +L_B along X for BX, along Y for BY, ...).

Thesis Eqs 4.1–4.8 and Table 2.6 are written in this frame.  A ball-bar program and its software may draw
the samples elsewhere: a 90° arc started at the software's 0° on its X axis draws B = 0° at +X, a plane seen
from the other side mirrors it, a bar set up on the other side of the W ball reverses ΔL.  The **reading
convention** of a run says where its samples were drawn: the plot direction of the sample at angle 0° and
at 90° of the motion (B for B patterns, C for C patterns), each a unit vector in the pattern's plane in
machine axes.  The offsets the software reports, ``e_r`` (first and second component of the pattern, ex/ez
or ex/ey, along the machine axes its plot is labelled with), then relate to the machine frame by

    ΔL(angle) = e_m · u_m(angle) = e_r · (cos(angle)·d0 + sin(angle)·d90)   for every angle,

so ``e_m = U⁻¹ D e_r`` with ``U = [u_m(0°); u_m(90°)]`` and ``D = [d0; d90]`` (both 2 × 2, rows).  Named
conventions (:data:`CONVENTIONS`):

* ``"thesis"`` — the reading the thesis applies to its Table 4.4 (Eqs 4.10–4.18): ``D = U``, the identity.
* ``"machine"`` — derived from the commands alone: each sample drawn at the direction, from the programmed
  arc's centre, of the programmed position (what a ball-bar software shows when it is given the programmed
  arc).  For ten patterns this is the thesis' reading; for the tangential patterns BT and CT the programmed
  position leads the B/C angle by ``atan(L_B/R_B)`` / ``atan(L_B/R_C)``, and so do the offsets
  (:func:`machine_directions` computes it from :func:`~mtmcal_bayes.patterns.pattern_commands`).
* a geometry string, ``"B0=+X,B90=+Z"`` for a B pattern or ``"C0=-Y,C90=+X"`` for a C pattern: where the
  sample at 0° and at 90° of the motion was drawn.  A bar on the other side of the W ball than Tables 2.2/2.3
  reverses ΔL: both directions turned, e.g. ``"B0=-Z,B90=-X"`` for BY with the T ball at Y = −L_B.

A trace (ΔL against angle, CW and CCW) is read exactly as its offsets would be entered: fitted in the
thesis' frame with its angle column as the angle, then converted by the run's convention (under
``"thesis"`` the angle column is the machine's B or C angle).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .patterns import B_PATTERNS, COMPONENTS, pattern_commands, polar_angle

#: the named conventions: the thesis' reading of Table 4.4, and the one derived from the programmed motion
CONVENTIONS = ("thesis", "machine")
#: the convention of a campaign that states none
DEFAULT = "thesis"

_AXES = {"X": 0, "Y": 1, "Z": 2}
_GEOMETRY = re.compile(r"^\s*([A-Z])0\s*=\s*([+-][XYZ])\s*,\s*([A-Z])90\s*=\s*([+-][XYZ])\s*$")


class ConventionError(ValueError):
    """A convention that cannot be used for a run: the message says why (the reader adds file and key)."""


@dataclass(frozen=True)
class PatternFrame:
    """How the samples of one run stand in the machine frame: ``letter`` the axis whose angle they are drawn
    against (``"B"``), ``components`` the pattern's two offsets (``("ex", "ez")``), ``axes`` the machine axes they
    lie along (``("X", "Z")``), ``basis`` ``U`` (2, 2; rows the machine frame's directions of the samples at 0° and
    90° of the motion, in ``axes`` coordinates) and ``programmed()`` the ``"machine"`` convention's ``D`` (2, 2).
    The thesis' patterns have theirs from Tables 2.2/2.3 (:func:`thesis_frame`); a described machine's from its
    chain (:mod:`mtmcal_bayes.pattern_frames`)."""

    letter: str
    components: tuple[str, str]
    axes: tuple[str, str]
    basis: np.ndarray
    programmed: Callable[[], np.ndarray]


def thesis_frame(pattern: str, *, R_B: float, Z_C: float, R_C: float, L_B: float,
                 cr_geometry: str = "RC-LB") -> PatternFrame:
    """The frame of a thesis pattern at its lever arms (mm)."""
    return PatternFrame("B" if pattern in B_PATTERNS else "C", COMPONENTS[pattern], plane_axes(pattern),
                        machine_basis(pattern, cr_geometry),
                        lambda: machine_directions(pattern, R_B=R_B, Z_C=Z_C, R_C=R_C, L_B=L_B,
                                                   cr_geometry=cr_geometry))


def _frame(pattern) -> PatternFrame:
    """``pattern`` as a frame for what needs only its letter and axes (a thesis pattern's name, or a frame)."""
    if isinstance(pattern, PatternFrame):
        return pattern
    return PatternFrame("B" if pattern in B_PATTERNS else "C", COMPONENTS[pattern], plane_axes(pattern),
                        machine_basis(pattern), lambda: machine_basis(pattern))


def plane_axes(pattern: str) -> tuple[str, str]:
    """The machine axes of a pattern's two components: ``("X", "Z")`` for B patterns, ``("X", "Y")`` for C."""
    return tuple(c[1].upper() for c in COMPONENTS[pattern])  # type: ignore[return-value]


def _unit(direction: str, axes: tuple[str, str]) -> np.ndarray:
    """``"+Z"`` as a 2-vector in a pattern's plane ``(first axis, second axis)``."""
    v = np.zeros(2)
    v[axes.index(direction[1])] = 1.0 if direction[0] == "+" else -1.0
    return v


def machine_basis(pattern: str, cr_geometry: str = "RC-LB") -> np.ndarray:
    """``U`` (2, 2): rows the machine frame's directions ``u_m(0°)`` and ``u_m(90°)`` of the pattern."""
    if pattern in B_PATTERNS:
        phi = np.radians([0.0, 90.0])
        return np.c_[np.sin(phi), np.cos(phi)]
    psi = polar_angle(pattern, np.radians([0.0, 90.0]), cr_geometry)
    return np.c_[np.cos(psi), np.sin(psi)]


def machine_directions(pattern: str, *, R_B: float, Z_C: float, R_C: float, L_B: float,
                       cr_geometry: str = "RC-LB") -> np.ndarray:
    """``D`` (2, 2) of the ``"machine"`` convention: rows the directions, from the programmed arc's centre, of the
    programmed position at 0° and at 90° of the motion (thesis Tables 2.2/2.3), in the pattern's plane."""
    cmd = pattern_commands(pattern, R_B=R_B, Z_C=Z_C, R_C=R_C, L_B=L_B, angles_deg=np.array([0.0, 90.0, 180.0, 270.0]),
                           cr_geometry=cr_geometry)
    pts = np.c_[cmd.X, cmd.Z] if pattern in B_PATTERNS else np.c_[cmd.X, cmd.Y]
    # the arc's centre: midpoint of the positions half a turn apart (the commands are circles in the angle)
    centre = 0.5 * (pts[0] + pts[2])
    d = pts[:2] - centre
    return d / np.linalg.norm(d, axis=1, keepdims=True)


def parse_geometry(text: str, pattern: str | PatternFrame) -> np.ndarray:
    """``D`` (2, 2) of a geometry string such as ``"B0=+X,B90=+Z"`` for ``pattern`` (a thesis pattern's name or a
    run's :class:`PatternFrame`); :class:`ConventionError` when it is malformed, of another axis, outside the
    pattern's plane or not a right angle."""
    frame = _frame(pattern)
    m = _GEOMETRY.match(text)
    want, axes = frame.letter, frame.axes
    first = np.argmax(np.abs(frame.basis), axis=1)  # the machine frame's own reading, as the example
    example = f'"{want}0=+{axes[first[0]]},{want}90=+{axes[first[1]]}"'
    name = pattern if isinstance(pattern, str) else f"{want} pattern"
    if not m:
        raise ConventionError(f"unknown convention {text!r} (expected one of {', '.join(CONVENTIONS)} or where the "
                              f"samples at 0° and 90° were drawn, e.g. {example})")
    a0, d0, a90, d90 = m.groups()
    if a0 != want or a90 != want:
        raise ConventionError(f"{text!r} names the {a0 if a0 != want else a90} angle, but pattern {name} turns "
                              f"the {want} axis (e.g. {example})")
    for d in (d0, d90):
        if d[1] not in axes:
            raise ConventionError(f"{text!r}: {d} is not in the {'/'.join(axes)} plane of pattern {name}")
    if d0[1] == d90[1]:
        raise ConventionError(f"{text!r}: the samples at 0° and 90° cannot both be drawn along {d0[1]}")
    return np.vstack([_unit(d0, axes), _unit(d90, axes)])


def geometry_string(D: np.ndarray, pattern: str | PatternFrame) -> str:
    """The geometry string of plot directions ``D`` (rows: 0°, 90°; each along one axis of the pattern's plane):
    the inverse of :func:`parse_geometry`."""
    frame = _frame(pattern)
    word = lambda v: ("+" if v[int(np.argmax(np.abs(v)))] > 0 else "-") + frame.axes[int(np.argmax(np.abs(v)))]  # noqa: E731
    return f"{frame.letter}0={word(D[0])},{frame.letter}90={word(D[1])}"


def frame_directions(convention: str, frame: PatternFrame) -> np.ndarray:
    """``D`` (2, 2) of ``convention`` for a run of ``frame``."""
    if convention == "thesis":
        return frame.basis
    if convention == "machine":
        return frame.programmed()
    return parse_geometry(convention, frame)


def frame_matrix(convention: str, frame: PatternFrame) -> np.ndarray:
    """``M`` (2, 2) with ``e_machine = M @ e_reported`` for a run of ``frame`` read in ``convention``."""
    return np.linalg.solve(frame.basis, frame_directions(convention, frame))


def directions(convention: str, pattern: str, *, R_B: float, Z_C: float, R_C: float, L_B: float,
               cr_geometry: str = "RC-LB") -> np.ndarray:
    """``D`` (2, 2) of ``convention`` for one run of thesis ``pattern`` (lever arms in mm)."""
    return frame_directions(convention, thesis_frame(pattern, R_B=R_B, Z_C=Z_C, R_C=R_C, L_B=L_B,
                                                     cr_geometry=cr_geometry))


def to_machine_matrix(convention: str, pattern: str, **geometry) -> np.ndarray:
    """``M`` (2, 2) with ``e_machine = M @ e_reported`` (thesis ``pattern``; ``geometry``: R_B, Z_C, R_C, L_B,
    cr_geometry)."""
    geometry.setdefault("cr_geometry", "RC-LB")
    return frame_matrix(convention, thesis_frame(pattern, **geometry))


def frame_describe(convention: str, frame: PatternFrame) -> str:
    """Where a convention draws the samples of a run of ``frame``, in words: ``"B = 0° at +Z, B = 90° at +X"``."""
    D, axes, angle = frame_directions(convention, frame), frame.axes, frame.letter

    def word(v):
        k = int(np.argmax(np.abs(v)))
        if abs(abs(v[k]) - 1.0) < 1e-9:
            return f"{'+' if v[k] > 0 else '-'}{axes[k]}"
        return f"{np.degrees(np.arctan2(v[1], v[0])):.1f}° from +{axes[0]} towards +{axes[1]}"

    return f"{angle} = 0° at {word(D[0])}, {angle} = 90° at {word(D[1])}"


def describe(convention: str, pattern: str, **geometry) -> str:
    """:func:`frame_describe` for thesis ``pattern`` at its lever arms."""
    geometry.setdefault("cr_geometry", "RC-LB")
    return frame_describe(convention, thesis_frame(pattern, **geometry))


def run_geometry(run, ballbar) -> dict:
    """The lever arms a run's convention may depend on (:func:`directions`' keyword arguments)."""
    setup, mount = ballbar.setups[run.setup], ballbar.mounts[run.mount]
    return {"R_B": setup.R_B, "Z_C": mount.Z_C, "R_C": mount.R_C, "L_B": ballbar.length,
            "cr_geometry": ballbar.cr_geometry}


def run_convention(run, ballbar) -> str:
    """The convention a run is read in: its own, else the campaign's ``[ballbar] convention``."""
    return run.convention or ballbar.convention


def run_frame(run, ballbar) -> PatternFrame:
    """The frame of a run: its machine's (``ballbar.pattern_frames``, set when a described machine's campaign is
    read), else the thesis' Tables 2.2/2.3 at the run's lever arms."""
    if ballbar.pattern_frames is not None:
        return ballbar.pattern_frames(run, ballbar)
    return thesis_frame(run.pattern, **run_geometry(run, ballbar))


def run_matrix(run, ballbar) -> np.ndarray:
    """``M`` (2, 2) of a run: machine-frame offsets = ``M @`` reported offsets."""
    return frame_matrix(run_convention(run, ballbar), run_frame(run, ballbar))


def reads_as_thesis(ballbar) -> bool:
    """Whether every run of ``ballbar`` is read as the thesis reads it (its convention's matrix is the identity)."""
    return all(np.allclose(run_matrix(run, ballbar), np.eye(2)) for run in ballbar.runs)


def check_run(run, ballbar) -> None:
    """:class:`ConventionError` when a run's convention cannot be applied to it: a malformed one, or one that
    mixes the two components of a run that gives only one of them."""
    M = run_matrix(run, ballbar)
    comps = run_frame(run, ballbar).components
    if len(run.repeats) < 2 and not np.allclose(M, np.diag(np.diag(M))):
        have = next(iter(run.repeats), comps[0])
        raise ConventionError(f"convention {run_convention(run, ballbar)!r} mixes {comps[0]} and {comps[1]} of "
                              f"pattern {run.pattern}, and the run gives only {have}: give both components")


def reads_machine_frame(run, ballbar) -> bool:
    """Whether a run's offsets are read in the machine frame itself (the ``"thesis"`` convention, ``D = U``): on any
    machine, with any pattern, its reported offsets are the machine frame's."""
    return run_convention(run, ballbar) == "thesis"


def machine_repeats(run, ballbar) -> dict[str, np.ndarray]:
    """The run's repeats in the machine frame, ``{component: (r,)}`` mm (only the components it gives)."""
    if reads_machine_frame(run, ballbar):
        return dict(run.repeats)
    M = run_matrix(run, ballbar)
    comps = run_frame(run, ballbar).components
    if np.allclose(M, np.eye(2)):
        return dict(run.repeats)
    if np.allclose(M, np.diag(np.diag(M))):
        return {c: M[comps.index(c), comps.index(c)] * np.asarray(v) for c, v in run.repeats.items()}
    reported = np.vstack([np.asarray(run.repeats[c], dtype=float) for c in comps])  # (2, r)
    machine = M @ reported
    return {c: machine[i] for i, c in enumerate(comps)}


def reported_values(run, ballbar, machine: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Machine-frame offsets ``{component: (r,)}`` as the run's convention reports them (the inverse of
    :func:`machine_repeats`); every component of the pattern is needed unless the convention keeps them apart."""
    if reads_machine_frame(run, ballbar):
        return {c: np.asarray(v) for c, v in machine.items()}
    M = run_matrix(run, ballbar)
    comps = run_frame(run, ballbar).components
    if np.allclose(M, np.diag(np.diag(M))):
        return {c: np.asarray(v) / M[comps.index(c), comps.index(c)] for c, v in machine.items()}
    out = np.linalg.solve(M, np.vstack([np.asarray(machine[c], dtype=float) for c in comps]))
    return {c: out[i] for i, c in enumerate(comps)}


def check_convention_name(value: str) -> None:
    """:class:`ConventionError` unless ``value`` is a named convention or a geometry string (of either axis)."""
    if value in CONVENTIONS:
        return
    m = _GEOMETRY.match(value)
    if not m or m.group(1) != m.group(3):
        raise ConventionError(f"unknown convention {value!r} (expected one of {', '.join(CONVENTIONS)}, or where a "
                              "run's samples at 0° and 90° were drawn, e.g. \"B0=+X,B90=+Z\" or, about a "
                              "described machine's A axis, \"A0=+Y,A90=+Z\")")
