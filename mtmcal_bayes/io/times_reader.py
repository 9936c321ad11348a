"""The machine-time model from a ``--times FILE.toml`` or a campaign's ``[design.times]`` (docs/design.md).

::

    # times.toml: minutes, any subset of the items
    tool_change_min = 12
    reclamp_w_ball_min = 8
    feed_mm_per_min = 1500

Unknown keys, non-numbers, negative or absurd values are one :class:`~mtmcal_bayes.errors.InputError`
naming the file and the key.
"""

from __future__ import annotations

from ..errors import InputError
from ..machine_time import TIME_KEYS, TimeModel
from .textfiles import read_user_text
from .toml_reader import TomlReader, parse_toml


def checked_times(table: dict, source: str, path: str = "") -> dict:
    """``table`` (keys as :class:`TimeModel`'s fields) checked: the values, or the first problem as an
    :class:`InputError` naming ``source`` and the key (``path`` prefixes it)."""
    r = TomlReader(str(source))
    r.check_keys(table, set(TIME_KEYS), path)
    key = lambda k: f"{path}.{k}" if path else k  # noqa: E731
    values = {}
    for k, v in table.items():
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise InputError(source, key(k), f"expected a number, got {v!r}")
        values[k] = v
    probe = TimeModel.__new__(TimeModel)  # check every value before building: the first problem names its key
    for k in TIME_KEYS:
        object.__setattr__(probe, k, values.get(k, getattr(TimeModel, k)))
    for k, _, why in probe.problems():
        raise InputError(source, key(k), why)
    return values


def time_model_from_table(table: dict, source: str, path: str = "") -> TimeModel:
    """The time model of ``table``, the defaults for what it does not give (errors as :func:`checked_times`)."""
    return TimeModel(**checked_times(table, source, path))


def read_times_table(path) -> dict:
    """The checked items of a ``--times`` file."""
    doc = parse_toml(read_user_text(path, "times file"), str(path))
    return checked_times(doc, str(path))


def read_times(path) -> TimeModel:
    """The time model of a ``--times`` file."""
    return TimeModel(**read_times_table(path))


__all__ = ["read_times", "read_times_table", "checked_times", "time_model_from_table"]
