"""Raw ball-bar traces: reading ``angle_deg, dL_um, direction`` CSV files and extracting eccentricities.

Each direction (CW, CCW) is fitted separately, ``ΔL = r0 + e_a cos ψ + e_b sin ψ`` with ψ the direction each sample
stands for as the chain's models read a simulated trace (:func:`~mtmcal_bayes.machines.patterns.fit_basis`), and the
two are averaged (thesis Sec 4.3.2); a file must hold both.  The same for every machine: the caller gives ψ of the
angle column (:func:`read_run_trace`).
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass

import numpy as np

from .. import units
from ..errors import InputError
from ..machines.patterns import (
    axis_of,
    components,
    default_arc_deg,
    fit_basis,
    pattern_commands,
)
from .textfiles import read_user_text

DIRECTIONS = ("CW", "CCW")


@dataclass
class TraceExtraction:
    """Eccentricities of one trace file: ``values`` component -> mm (CW/CCW average), fit rms per direction, mm."""

    values: dict[str, float]
    rms: dict[str, float]


def read_trace(path, L_B: float, *, psi_of, components: tuple[str, str], order: tuple[str, ...] | None = None,
               axis: str = "", arc_span_deg: float | None = None) -> TraceExtraction:
    """Read a trace CSV and extract a pattern's eccentricities; bad content names file and line.

    ``psi_of(angles_deg (k,)) -> (k,)`` rad: the direction each sample stands for at the swivelled axis' angle
    (``axis``); ``components``: the pattern's two, along ``cos ψ`` and ``sin ψ``; ``order``: those to return, in
    this order (default both); ``arc_span_deg``: the span of the pattern's arc where it is at
    most half a turn (a swing, whose trace spans 30° to 180°: more is another axis' trace), None for a turn (whose
    trace spans at least 90°).  L_B the bar length, mm."""
    text = read_user_text(path, "trace CSV file")
    src = str(path)
    rows = list(csv.reader(io.StringIO(text)))
    rows = [r for r in rows if r and any(c.strip() for c in r)]
    if not rows:
        raise InputError(src, None, "empty file (expected columns angle_deg, dL_um, direction)")
    header = [c.strip() for c in rows[0]]
    if header != ["angle_deg", "dL_um", "direction"]:
        raise InputError(src, "line 1", f"expected the header angle_deg,dL_um,direction, got {','.join(header)!r}")
    data: dict[str, list[tuple[float, float]]] = {d: [] for d in DIRECTIONS}
    for no, r in enumerate(rows[1:], start=2):
        if len(r) != 3:
            raise InputError(src, f"line {no}", f"expected 3 columns, got {len(r)}")
        try:
            a, dl = float(r[0]), float(r[1])
        except ValueError:
            raise InputError(src, f"line {no}", f"not a number: {r[0].strip()!r} or {r[1].strip()!r}") from None
        if not (math.isfinite(a) and math.isfinite(dl)):
            raise InputError(src, f"line {no}", "NaN or infinite value")
        d = r[2].strip().upper()
        if d not in DIRECTIONS:
            raise InputError(src, f"line {no}", f"direction must be CW or CCW, got {r[2].strip()!r}")
        if abs(a) > 360.0:
            raise InputError(src, f"line {no}", f"angle_deg = {a:g} is outside -360…360°")
        if units.to_internal(abs(dl), "um") >= L_B:
            raise InputError(src, f"line {no}", f"dL_um = {dl:g} is not below the bar length "
                             f"L_B = {L_B:g} mm: not a ball-bar reading")
        data[d].append((a, dl))
    fits = {}
    for d, pts in data.items():
        if not pts:
            continue
        arr = np.array(pts)
        span = np.ptp(arr[:, 0])
        if arc_span_deg is not None and span > 180.0:
            raise InputError(src, None, f"{d} trace spans {span:g}°, more than the 180° a {axis} pattern can swing "
                             f"(its arc spans {arc_span_deg:g}°): is this a trace of another axis?")
        if len(arr) < 4 or span < (30.0 if arc_span_deg is not None else 90.0):
            raise InputError(src, None, f"{d} trace too short to fit ({len(arr)} points over {span:g}°)")
        psi = psi_of(arr[:, 0])
        fits[d] = fit_eccentricity(psi, units.to_internal(arr[:, 1], "um"))
    if not fits:
        raise InputError(src, None, "no data rows")
    missing = [d for d in DIRECTIONS if d not in fits]
    if missing:  # each repeat is the mean of a CW and a CCW run (thesis Sec 4.3.2); one alone is not guessed
        raise InputError(src, None, f"no {missing[0]} rows: a trace needs both directions, CW and CCW "
                         "(their mean cancels the direction-dependent errors)")
    mean = np.mean([f[0] for f in fits.values()], axis=0)  # (2,): along cos ψ, sin ψ
    values = {c: float(mean[components.index(c)]) for c in (order or components)}
    return TraceExtraction(values, {d: float(f[1]) for d, f in fits.items()})


def fit_eccentricity(psi: np.ndarray, dL: np.ndarray) -> tuple[np.ndarray, float]:
    """Least squares ``dL = r0 + e_a cos ψ + e_b sin ψ`` over (k,) samples: ``((e_a, e_b), rms residual)``, mm."""
    D = fit_basis(psi)
    coef, *_ = np.linalg.lstsq(D, dL, rcond=None)
    return coef[1:], float(np.sqrt(np.mean((dL - D @ coef) ** 2)))


def read_run_trace(path, ballbar, desc, run, *, order: tuple[str, ...] | None = None):
    """The eccentricities of ``run`` in one trace file (:func:`read_trace`): its angle
    column the swivelled axis' commanded angle, each sample standing for the direction ψ its pattern's commands give
    there (the polar angle of a radial bar; :func:`~mtmcal_bayes.machines.patterns.pattern_commands`), the result in
    the pattern's components as the ``"thesis"`` convention reads them (those of ``order``, in its order; default the
    engine's two)."""
    setup, mount = ballbar.setups[run.setup], ballbar.mounts[run.mount]
    ax = axis_of(desc, run.pattern)

    def psi_of(angles_deg: np.ndarray) -> np.ndarray:
        return pattern_commands(desc, run.pattern, length=setup.R_B, ball=mount.centre(), bar=ballbar.length,
                                arc_deg=angles_deg, hold_deg=run.hold_deg, reverse=ballbar.bar_reversed(run)).psi

    arc = ballbar.arc_of(run)
    span = float(np.ptp(default_arc_deg(ax) if arc is None else arc))
    return read_trace(path, ballbar.length, psi_of=psi_of, components=components(desc, run.pattern), order=order,
                      axis=ax.letter, arc_span_deg=span if span <= 180.0 else None)
