"""JSON as the command line prints it: floats to 10 significant digits, NaN and infinities as null."""

from __future__ import annotations

import json
import math


def rounded(obj, digits: int = 10):
    """``obj`` with every float rounded to ``digits`` significant digits; NaN/inf become None."""
    if isinstance(obj, float):
        return float(f"{obj:.{digits}g}") if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: rounded(v, digits) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [rounded(v, digits) for v in obj]
    return obj


def json_text(obj) -> str:
    """Indented JSON of ``obj`` (see :func:`rounded`), non-ASCII kept (µm, ″)."""
    return json.dumps(rounded(obj), indent=2, ensure_ascii=False)
