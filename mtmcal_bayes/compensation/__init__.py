"""Compensation of NC programs for the identified deviations (``compensate``), on any machine.

* :class:`CompensationResult` — the compensated program, per block the corrections, the residual error from
  posterior draws and the tool tilts X/Y/Z cannot correct (:mod:`.result`; the options a compensation is
  asked with, :mod:`.options`: :data:`METHODS`, :data:`VALUES`, :data:`POINTS`).
* :func:`~.compensate.compensate` — the one path of every machine: the program's commands, the posterior's
  draws, the values, Newton through the machine's kinematics (:mod:`.inverse`; the description's chain,
  :mod:`.chain_kinematics`), the residual band, the tilts.

A machine's plug-in contributes only what is its own (the thesis': its models' tool point in their model frame,
Eqs 3.4–3.13 as printed, its ball-bar values, its default posterior; ``mtmcal_bayes.plugins.thesis``): the engine
asks the machine (:func:`mtmcal_bayes.machines.plugins.provided`).
"""

from .options import METHODS, N_DRAWS, OFF_TOOL_MM, POINTS, SIGMA_MODEL_UM, VALUES
from .result import CompensationResult

__all__ = ["METHODS", "VALUES", "POINTS", "OFF_TOOL_MM", "N_DRAWS", "SIGMA_MODEL_UM", "CompensationResult"]
