"""What a compensation gives on any machine (:mod:`.compensate`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .. import units
from ..io.textfiles import write_text_atomic


@dataclass
class CompensationResult:
    """Compensated program text and, per motion block (k), corrections and residuals in µm."""

    text: str
    program: str  # the source program's file name
    xyz: np.ndarray  # (k, 3) original NC X, Y, Z, mm
    xyz_c: np.ndarray  # (k, 3) compensated, mm
    residual_mean_um: np.ndarray  # (k,) mean length of the residual tool-point error over the draws
    residual_p95_um: np.ndarray  # (k,) its 95 % quantile
    error_before_um: np.ndarray  # (k,) length of the error of the original program at the used deviations
    not_compensable: list[dict] = field(default_factory=list)
    info: dict = field(default_factory=dict)
    output: str | None = None  # where :meth:`save` wrote the compensated program
    warnings: list[str] = field(default_factory=list)  # values the data do not determine, or that rest on priors
    reading_choice: dict | None = None  # deviations resting on the campaign's choice of reading (.reading_choice)
    #: the simultaneous band: the 95 % quantile over the draws of the largest residual over the blocks, µm
    residual_program_p95_um: float = float("nan")

    def save(self, path) -> None:
        """Write the compensated program to ``path`` (atomically)."""
        write_text_atomic(path, self.text)
        self.output = str(path)

    def to_text(self) -> str:
        """What ``compensate`` prints."""
        from .output import format_compensation

        return format_compensation(self)

    def to_json(self) -> dict:
        """What ``compensate --json`` prints: the method, corrections, residuals, what is not compensable."""
        return {**self.summary(), "program": self.program, "output": self.output}

    def summary(self) -> dict:
        """Corrections, tool-point errors before and after, and the tool tilts, in µm and ″."""
        corr = units.from_internal(self.xyz_c - self.xyz, "um")
        return {
            **self.info,
            "blocks": len(self.xyz),
            "correction_um": {"max_abs": {a: float(np.abs(corr[:, i]).max()) for i, a in enumerate("XYZ")},
                              "first_block": dict(zip("XYZ", map(float, corr[0])))},
            "error_before_um": {"max": float(self.error_before_um.max())},
            "residual_um": {"mean_max": float(self.residual_mean_um.max()),
                            "p95_max": float(self.residual_p95_um.max()),
                            "program_p95": float(self.residual_program_p95_um),
                            "per_block_p95": [float(v) for v in self.residual_p95_um]},
            "not_compensable": self.not_compensable,
            "warnings": self.warnings,
            **({"reading_choice": self.reading_choice} if self.reading_choice is not None else {}),
        }
