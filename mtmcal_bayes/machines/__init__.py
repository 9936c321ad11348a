"""Machines described, not coded (SPEC §19): descriptions, their location errors and their ISO 230-7 names."""

from .description import Axis, MachineDescription, Spindle
from .deviations import Deviation, generated
from .selection import redundant, selected

__all__ = ["Axis", "MachineDescription", "Spindle", "Deviation", "generated", "selected", "redundant"]
