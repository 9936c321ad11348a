"""``probe-fit``: the sphere a DPRNT file's probed points lie on (thesis Fig 5.13), with notes on the file."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from .. import units
from ..errors import MtmcalError, ParameterError
from ..io.dprnt import read_dprnt
from ..sphere import SphereFit, fit_sphere


@dataclass
class ProbeFit:
    """A sphere fitted to the ``n_points`` probed points of ``file``, and what the file itself says."""

    file: str
    n_points: int
    fit: SphereFit
    notes: list[str] = field(default_factory=list)

    def to_json(self) -> dict:
        f = self.fit
        return {
            "file": self.file, "n_points": self.n_points,
            "centre_mm": f.centre.tolist(), "radius_mm": f.radius,
            "fitted_radius_mm": f.fitted_radius, "stylus_radius_mm": f.stylus_radius,
            "rms_residual_um": units.from_internal(f.rms, "um"),
            "max_abs_residual_um": units.from_internal(float(abs(f.residuals).max()), "um"),
            "notes": self.notes,
        }

    def to_text(self) -> str:
        f = self.fit
        x, y, z = f.centre
        radius = f"  radius   {f.radius:.4f} mm"
        if f.stylus_radius:
            radius += f" (fitted {f.fitted_radius:.4f} mm − stylus {f.stylus_radius:g} mm)"
        lines = [f"Sphere fit of {self.n_points} probed points in {self.file}",
                 f"  centre   X {x:.4f}  Y {y:.4f}  Z {z:.4f} mm", radius,
                 f"  residual rms {units.from_internal(f.rms, 'um'):.2f} µm, "
                 f"max |{units.from_internal(float(abs(f.residuals).max()), 'um'):.2f}| µm"]
        return "\n".join(lines + [f"  note: {n}" for n in self.notes])


def probe_fit(path, *, stylus_radius_mm: float | None = None) -> ProbeFit:
    """Least-squares sphere through the points of the DPRNT file at ``path``.

    ``stylus_radius_mm`` is subtracted from the fitted radius (the points are
    stylus-ball centres; the centre is unchanged).
    """
    pts = read_dprnt(path)
    if stylus_radius_mm is not None and not math.isfinite(stylus_radius_mm):
        raise ParameterError("stylus_radius_mm", f"{stylus_radius_mm} is not a finite number")
    try:
        fit = fit_sphere(pts.xyz, stylus_radius_mm or 0.0)
    except MtmcalError as exc:
        raise MtmcalError(f"{path}: {exc}") from None
    notes = []
    if pts.declared is not None and pts.declared != len(pts.xyz):
        notes.append(f"header declares {pts.declared} points, the file holds {len(pts.xyz)}")
    if len({tuple(r) for r in pts.bc}) > 1:
        notes.append("points were probed at different B/C positions; fitted as one sphere in machine coordinates")
    return ProbeFit(str(path), len(pts.xyz), fit, notes)
