"""A truth as the ``[truth]`` table of a campaign file (file units), for the thesis machine and described ones."""

from __future__ import annotations

from .. import units
from ..campaign import Truth
from ..parameters import quantity_unit


def truth_to_dict(t: Truth) -> dict:
    unit = {n: quantity_unit(n) for n in t.deviations}  # the thesis' names, or a described machine's ISO symbols
    d: dict = {"deviations": {f"{n}_{unit[n]}": units.from_internal(v, unit[n]) for n, v in t.deviations.items()}}
    for group in ("setups", "mounts", "probe", "rtest"):
        vals = getattr(t, group)
        if vals:
            d[group] = {oid: {f"{k}_um": units.from_internal(v, "um") for k, v in kv.items()}
                        for oid, kv in vals.items()}
    return d
