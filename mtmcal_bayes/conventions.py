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
  (:func:`mtmcal_bayes.pattern_frames.chain_frame` computes it from the machine's chain).
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
    Every machine's come from its chain (:mod:`mtmcal_bayes.pattern_frames`; the thesis' are those of Tables
    2.2/2.3)."""

    letter: str
    components: tuple[str, str]
    axes: tuple[str, str]
    basis: np.ndarray
    programmed: Callable[[], np.ndarray]
    pattern: str = ""  # the run's pattern, for messages


def _unit(direction: str, axes: tuple[str, str]) -> np.ndarray:
    """``"+Z"`` as a 2-vector in a pattern's plane ``(first axis, second axis)``."""
    v = np.zeros(2)
    v[axes.index(direction[1])] = 1.0 if direction[0] == "+" else -1.0
    return v


def parse_geometry(text: str, frame: PatternFrame) -> np.ndarray:
    """``D`` (2, 2) of a geometry string such as ``"B0=+X,B90=+Z"`` for a run of ``frame``; :class:`ConventionError`
    when it is malformed, of another axis, outside the pattern's plane or not a right angle."""
    m = _GEOMETRY.match(text)
    want, axes = frame.letter, frame.axes
    first = np.argmax(np.abs(frame.basis), axis=1)  # the machine frame's own reading, as the example
    example = f'"{want}0=+{axes[first[0]]},{want}90=+{axes[first[1]]}"'
    name = frame.pattern or f"of axis {want}"
    if not m:
        raise ConventionError(f"unknown convention {text!r} (expected one of {', '.join(CONVENTIONS)} or where the "
                              f"samples at 0° and 90° were drawn, e.g. {example})")
    a0, d0, a90, d90 = m.groups()
    if a0 != want or a90 != want:
        raise ConventionError(f"{text!r} names the {a0 if a0 != want else a90} angle, but pattern {name} turns "
                              f"the {want} axis (e.g. {example})")
    for d in (d0, d90):
        if d[1] not in axes:
            raise ConventionError(f"{text!r}: {d} is not in the {'/'.join(sorted(axes))} plane of pattern {name}")
    if d0[1] == d90[1]:
        raise ConventionError(f"{text!r}: the samples at 0° and 90° cannot both be drawn along {d0[1]}")
    return np.vstack([_unit(d0, axes), _unit(d90, axes)])


def geometry_string(D: np.ndarray, frame: PatternFrame) -> str:
    """The geometry string of plot directions ``D`` (rows: 0°, 90°; each along one axis of the pattern's plane)
    for a run of ``frame``: the inverse of :func:`parse_geometry`."""
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


def run_convention(run, ballbar) -> str:
    """The convention a run is read in: its own, else the campaign's ``[ballbar] convention``."""
    return run.convention or ballbar.convention


def run_frame(run, ballbar) -> PatternFrame:
    """The frame of a run: its machine's (``ballbar.pattern_frames``, from its chain: set when a campaign is read or
    built); :class:`ConventionError` for a ball bar without frames (outside a campaign, or of a machine without a
    description, its runs read otherwise than in the machine frame)."""
    if ballbar.pattern_frames is None:
        raise ConventionError(f"run {run.label} is read in convention {run_convention(run, ballbar)!r}, and its "
                              "ball bar has no pattern frames to read it against (a ball bar outside a campaign, or "
                              "of a machine without a description: set its pattern_frames, pattern_frames.chain_frame)")
    return ballbar.pattern_frames(run, ballbar)


def run_matrix(run, ballbar) -> np.ndarray:
    """``M`` (2, 2) of a run: machine-frame offsets = ``M @`` reported offsets."""
    return frame_matrix(run_convention(run, ballbar), run_frame(run, ballbar))


def reads_as_thesis(ballbar) -> bool:
    """Whether every run of ``ballbar`` is read as the thesis reads it (its convention's matrix is the identity)."""
    return all(np.allclose(run_matrix(run, ballbar), np.eye(2)) for run in ballbar.runs)


def check_run(run, ballbar) -> None:
    """:class:`ConventionError` when a run's convention cannot be applied to it: a malformed one, or one that
    mixes the two components of a run that gives only one of them, or not one of each per repeat."""
    M = run_matrix(run, ballbar)
    comps = run_frame(run, ballbar).components
    if np.allclose(M, np.diag(np.diag(M))):
        return
    first, second = sorted(comps)
    mixes = f"convention {run_convention(run, ballbar)!r} mixes {first} and {second} of pattern {run.pattern}"
    if len(run.repeats) < 2:
        have = next(iter(run.repeats), comps[0])
        raise ConventionError(f"{mixes}, and the run gives only {have}: give both components")
    counts = {c: len(v) for c, v in run.repeats.items()}
    if len(set(counts.values())) > 1:
        raise ConventionError(f"{mixes}, and the run gives {' and '.join(f'{n} of {c}' for c, n in counts.items())}: "
                              "give both components of every repeat")


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
    return {c: machine[comps.index(c)] for c in run.repeats}  # in the run's own order of its components


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
    return {c: out[comps.index(c)] for c in machine}


def check_convention_name(value: str) -> None:
    """:class:`ConventionError` unless ``value`` is a named convention or a geometry string (of either axis)."""
    if value in CONVENTIONS:
        return
    m = _GEOMETRY.match(value)
    if not m or m.group(1) != m.group(3):
        raise ConventionError(f"unknown convention {value!r} (expected one of {', '.join(CONVENTIONS)}, or where a "
                              "run's samples at 0° and 90° were drawn, e.g. \"B0=+X,B90=+Z\" or, about a "
                              "described machine's A axis, \"A0=+Y,A90=+Z\")")
