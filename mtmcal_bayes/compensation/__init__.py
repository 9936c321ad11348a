"""Compensation of NC programs for the identified deviations (``compensate``), on any machine.

* :class:`CompensationResult` — the compensated program, per block the corrections, the residual error from
  posterior draws and the tool tilts X/Y/Z cannot correct (:mod:`.result`; the options a compensation is
  asked with, :mod:`.options`: :data:`METHODS`, :data:`VALUES`, :data:`POINTS`).
* :func:`~.through_chain.compensate_described` — exact Newton inversion through a described machine's chain.

The thesis machine's compensation (its kinematic models inverted exactly, Eqs 3.4–3.13 as printed, its ball-bar
values) and its measuring programs (Fig 4.30(a)) are the thesis plug-in's (``mtmcal_bayes.plugins.thesis``): the
engine asks a machine for its ``compensate`` and ``program``.
"""

from .options import METHODS, N_DRAWS, OFF_TOOL_MM, POINTS, SIGMA_MODEL_UM, VALUES
from .result import CompensationResult

__all__ = ["METHODS", "VALUES", "POINTS", "OFF_TOOL_MM", "N_DRAWS", "SIGMA_MODEL_UM", "CompensationResult"]
