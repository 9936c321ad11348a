"""Measurement planning: which extra ball-bar run reduces the uncertainty most (SPEC §6)."""

from .candidates import Candidate, read_candidates
from .catalogue import catalogue, feasibility
from .design import Planner
from .plan import PlanResult, best_measurement, plan

__all__ = ["Candidate", "catalogue", "feasibility", "read_candidates", "Planner", "PlanResult", "best_measurement", "plan"]
