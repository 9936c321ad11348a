"""Planned runs of a campaign (``planned = true``, docs/campaign-format.md): read alike on any machine."""

from __future__ import annotations

from ..campaign import PlannedRun
from .toml_reader import TomlReader, kind_of

#: most repeats a planned run may ask for
MAX_PLANNED_REPEATS = 10_000
#: the keys only a planned run (``planned = true``) has, on any machine
PLANNED_KEYS = ("repeats", "minutes", "why", "order")


def planned_run(r: TomlReader, t: dict, path: str, *, pattern: str, setup: str, mount: str) -> PlannedRun:
    """A run with ``planned = true``: how many repeats, and optionally minutes, why, order (its data checked absent
    by the caller, which knows the machine's keys)."""
    repeats = whole(r, t, "repeats", path, low=1, high=MAX_PLANNED_REPEATS, required=True,
                    what="the number of repeats to measure")
    order = whole(r, t, "order", path, low=1, high=None, required=False, what="the place in the measuring order")
    return PlannedRun(pattern, setup, mount, repeats, minutes=r.number(t, "minutes", path, required=False,
                                                                      nonnegative=True),
                      why=r.string(t, "why", path), order=order)


def planned_in_order(r: TomlReader, planned: list[tuple[int, PlannedRun]], path: str) -> list[PlannedRun]:
    """The planned runs in measuring order: as in the file, or sorted by ``order`` when they give one (then all
    must, each a different number)."""
    given = [(i, x) for i, x in planned if x.order is not None]
    if not given:
        return [x for _, x in planned]
    if len(given) < len(planned):
        i = next(i for i, x in planned if x.order is None)
        r.fail(f"{path}.runs[{i}]", "planned without order while other planned runs give one: give every planned "
               "run its order, or none (then the file's order is the measuring order)")
    seen: dict[int, int] = {}
    for i, x in given:
        j = seen.setdefault(x.order, i)
        if j != i:
            r.fail(f"{path}.runs[{i}].order", f"{x.order} is also the order of {path}.runs[{j}]: each planned run "
                   "has its own place in the measuring order")
    return [x for _, x in sorted(given, key=lambda ix: ix[1].order)]


def whole(r: TomlReader, t: dict, key: str, path: str, *, low: int, high: int | None, required: bool,
           what: str) -> int | None:
    """A whole number ``low`` ≤ n (≤ ``high``) at ``path.key``."""
    full = f"{path}.{key}"
    if key not in t:
        if required:
            r.fail(full, f"missing: {what} (a whole number)")
        return None
    v = t[key]
    if isinstance(v, float) and v.is_integer():
        v = int(v)
    if isinstance(v, bool) or not isinstance(v, int):
        r.fail(full, f"expected a whole number ({what}), got {kind_of(v) if not isinstance(v, float) else f'{v:g}'}")
    if v < low or (high is not None and v > high):
        r.fail(full, f"{v} is not {what}: expected a whole number from {low}" + (f" to {high}" if high else " up"))
    return v


__all__ = ["planned_run", "planned_in_order", "whole", "PLANNED_KEYS", "MAX_PLANNED_REPEATS"]
