"""The ISG CSV format of the ISG kernel's / Beckhoff TF5280 volumetric compensation, for machine position errors.

As its public documentation describes it (infosys.beckhoff.com, TF5280 "ISG CSV format", "Units of measure",
"List of parameters supported"): a header line naming the columns — position errors by their DIN ISO 230 names
(``Y0A Z0A X0B …``) — then the records below it, one for position errors (constant); row comments begin with
``//``; values in millimetres for offsets and radians for angles.  The names are the ISO 230-7 symbols without
their ``E_`` (``E_Y0A`` is ``Y0A``), with the same sign.

The same list names the ISG kernel's parameters of the kinematic model beside the position errors: ``PXA … PZC``
the centre of rotation of the A, B, C axis and ``VXA … VZC`` the axis' (modified) orientation.  An inclined axis
(SPEC §21), whose errors are named in its own basis and have no position-error name here, is written as its line:
a point (mm) and its unit direction, in the machine frame.
"""

from __future__ import annotations

import math

#: the position errors the format names: <X|Y|Z|A|B|C>0<X|Y|Z|A|B|C>
ISG_NAMES = tuple(f"{e}0{a}" for a in "XYZABC" for e in "XYZABC")
#: the kinematic parameters of a rotary axis' line: its centre of rotation P<X|Y|Z><A|B|C> (mm) and its orientation
#: V<X|Y|Z><A|B|C> (a unit vector's components)
LINE_NAMES = tuple(f"{kind}{c}{a}" for a in "ABC" for kind in "PV" for c in "XYZ")


def line_names(letter: str) -> tuple[tuple[str, str, str], ...]:
    """``(name, "point" or "direction", component)`` of rotary axis ``letter``'s line: ``("PXB", "point", "x")`` …
    ``("VZB", "direction", "z")``."""
    return tuple((f"{kind}{c.upper()}{letter}", what, c) for kind, what in (("P", "point"), ("V", "direction"))
                 for c in "xyz")


def isg_name(symbol: str) -> str | None:
    """The ISG name of an ISO 230-7 location-error symbol (``E_Y0A`` -> ``Y0A``), or None where the format has none
    (a spindle's errors relative to the axis carrying it, ``E_X(0C1)B``)."""
    name = symbol[2:] if symbol.startswith("E_") else symbol
    return name if name in ISG_NAMES else None


def isg_csv(values: dict[str, float], comments: list[str] = ()) -> str:
    """The text of an ISG CSV file of position errors: ``values`` {ISG name: value} in mm or rad, and an inclined
    axis' line {``PXB``: mm, ``VXB``: 1, …} (one record),
    ``comments`` each a ``//`` line before the header."""
    for name, v in values.items():
        if name not in ISG_NAMES and name not in LINE_NAMES:
            raise ValueError(f"{name!r} is not a position error or an axis parameter of the ISG CSV format")
        if not math.isfinite(v):
            raise ValueError(f"{name}: {v} is not a finite value")
    lines = [f"// {c}" for c in comments]
    if values:
        lines += [" ".join(values), " ".join(f"{v:.9g}" for v in values.values())]
    return "\n".join(lines) + "\n"
