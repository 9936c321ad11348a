"""Which machine description a campaign is of: a key that is equal exactly when two descriptions are the same.

A history is one machine measured again and again, and machines of one ``[machine] type`` pool their σ_model: both
need to know that two campaigns describe the same kinematics.  The key is the one the machine's plug-in gives it (the
thesis machine's ``"thesis"``), else a
sha256 (12 hex digits) of the description written out in full (:func:`~.description_writer.description_to_dict` with
the built-in name set aside: a built-in type and the same chain written out by hand are the same machine): its
configuration, axes (directions, points, travels), spindle, deviation selection and squareness form.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json

from ..machines.plugins import provided
from .description_writer import description_to_dict


def description_key(machine) -> str:
    """The key its plug-in gives the machine (the thesis machine's: ``"thesis"``), else 12 hex digits of its
    written-out description (module docstring)."""
    own = provided(machine, "description_key")
    if own is not None:
        return own
    full = description_to_dict(dataclasses.replace(machine.description, builtin=""))
    return hashlib.sha256(json.dumps(full, sort_keys=True).encode("utf-8")).hexdigest()[:12]


def description_label(machine) -> str:
    """The description in words: its plug-in's (``"thesis machine"``), a built-in type's name, or ``"described
    <configuration>"``."""
    own = provided(machine, "description_label")
    if own is not None:
        return own
    desc = machine.description
    return desc.builtin or f"described {desc.configuration}"
