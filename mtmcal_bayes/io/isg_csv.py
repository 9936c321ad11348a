"""The ISG CSV format of the ISG kernel's / Beckhoff TF5280 volumetric compensation, for machine position errors.

As its public documentation describes it (infosys.beckhoff.com, TF5280 "ISG CSV format", "Units of measure",
"List of parameters supported"): a header line naming the columns — position errors by their DIN ISO 230 names
(``Y0A Z0A X0B …``) — then the records below it, one for position errors (constant); row comments begin with
``//``; values in millimetres for offsets and radians for angles.  The names are the ISO 230-7 symbols without
their ``E_`` (``E_Y0A`` is ``Y0A``), with the same sign.
"""

from __future__ import annotations

import math

#: the position errors the format names: <X|Y|Z|A|B|C>0<X|Y|Z|A|B|C>
ISG_NAMES = tuple(f"{e}0{a}" for a in "XYZABC" for e in "XYZABC")


def isg_name(symbol: str) -> str | None:
    """The ISG name of an ISO 230-7 location-error symbol (``E_Y0A`` -> ``Y0A``), or None where the format has none
    (a spindle's errors relative to the axis carrying it, ``E_X(0C1)B``)."""
    name = symbol[2:] if symbol.startswith("E_") else symbol
    return name if name in ISG_NAMES else None


def isg_csv(values: dict[str, float], comments: list[str] = ()) -> str:
    """The text of an ISG CSV file of position errors: ``values`` {ISG name: value} in mm or rad (one record),
    ``comments`` each a ``//`` line before the header."""
    for name, v in values.items():
        if name not in ISG_NAMES:
            raise ValueError(f"{name!r} is not a position error of the ISG CSV format")
        if not math.isfinite(v):
            raise ValueError(f"{name}: {v} is not a finite value")
    lines = [f"// {c}" for c in comments]
    if values:
        lines += [" ".join(values), " ".join(f"{v:.9g}" for v in values.values())]
    return "\n".join(lines) + "\n"
