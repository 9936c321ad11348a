"""The fleet's cache: one JSON file per finished unit, named by the unit's key, written atomically.

A unit's key (:func:`~mtmcal_bayes.fleets.units.unit_key`) covers the content of its campaigns, the settings
and the package version, so an entry is valid wherever the campaign file lies and whoever runs it; a changed
file, seed or version simply misses.  Each entry is written the moment its unit finishes, through a temporary
file and ``os.replace``: a run killed at any point leaves whole entries or none, and the next run loads them
instead of computing them again.  Failures are not cached (the next run tries again).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

from ..io.textfiles import write_text_atomic
from .units import UNIT_FORMAT

#: the cache folder below ``-o DIR`` when no other is given
OUTPUT_CACHE = ".cache"


def default_cache(output) -> Path:
    """``<output>/.cache`` with an output folder, else the user's cache folder
    (``$XDG_CACHE_HOME/mtmcal-bayes/fleet``, by default ``~/.cache/mtmcal-bayes/fleet``)."""
    if output is not None:
        return Path(output) / OUTPUT_CACHE
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "mtmcal-bayes" / "fleet"


class UnitCache:
    """Entries ``<kind>-<key>.json`` in ``folder`` (created when the first entry is written)."""

    def __init__(self, folder: str | os.PathLike):
        self.folder = Path(folder)

    def path(self, kind: str, key: str) -> Path:
        return self.folder / f"{kind}-{key}.json"

    def get(self, kind: str, key: str) -> dict | None:
        """The stored ``{"result", "files", "elapsed_s"}`` of a unit, or None (missing, unreadable, not ours)."""
        try:
            doc = json.loads(self.path(kind, key).read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        if not isinstance(doc, dict) or doc.get("format") != UNIT_FORMAT or doc.get("key") != key:
            return None
        return {"result": doc["result"], "files": doc.get("files", {}), "elapsed_s": doc.get("elapsed_s", 0.0)}

    def put(self, kind: str, key: str, payload: dict) -> None:
        """Store a finished unit's payload (atomically: the entry is whole or absent)."""
        self.folder.mkdir(parents=True, exist_ok=True)
        doc = {"format": UNIT_FORMAT, "kind": kind, "key": key, **payload}
        write_text_atomic(self.path(kind, key), json.dumps(doc, ensure_ascii=False, allow_nan=False))
