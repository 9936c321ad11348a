"""NC programs: measuring programs of the patterns, and compensation of programs for the identified deviations.

* :func:`compensate` — rewrite X/Y/Z so the tool point reaches the programmed
  point (exact Newton inversion of a kinematic model, or thesis Eqs 3.4–3.13),
  with the residual error from posterior draws and the tool tilts that X/Y/Z
  cannot correct (:class:`CompensationResult`).
* :func:`measuring_program` — the NC program of a ball-bar pattern for a
  campaign's setup (thesis Fig 4.30(a)).
"""

from .compensate import (
           METHODS,
           OFF_TOOL_MM,
           CompensationResult,
           compensate,
           geometry_for,
)
from .measuring import measuring_program
from .values import VALUES, ballbar_values, posterior_draws

__all__ = ["METHODS", "OFF_TOOL_MM", "CompensationResult", "compensate", "geometry_for", "measuring_program",
           "VALUES", "ballbar_values", "posterior_draws"]
