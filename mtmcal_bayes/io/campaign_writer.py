"""Writing campaigns as TOML (``mtmcal-campaign/1``): file units, traces relative to the file, atomically."""

from __future__ import annotations

import os
from pathlib import Path

from ..campaign import Campaign
from ..machines.plugins import provided
from .description_writer import described_to_dict
from .campaign_reader import FORMAT
from .textfiles import write_text_atomic
from .tomlio import dumps


def campaign_to_dict(c: Campaign, save_dir: Path | None = None) -> dict:
    """The TOML document of a campaign (file units), as nested dicts.

    Trace files are written relative to ``save_dir`` (absolute when ``None``).
    """
    doc: dict = {"format": FORMAT}
    if c.date is not None:
        doc["date"] = c.date
    if c.temperature_C is not None:
        doc["temperature_C"] = c.temperature_C
    write = provided(c.machine, "campaign_document", described_to_dict)  # a plug-in's campaign keys
    return write(c, doc, save_dir)


def save_campaign(campaign: Campaign, path: str | os.PathLike, header: str | None = None) -> None:
    """Write ``campaign`` as TOML to ``path`` (atomically); ``header`` becomes a leading comment."""
    text = dumps(campaign_to_dict(campaign, Path(path).resolve().parent))
    if header:
        text = "".join(f"# {line}\n" for line in header.splitlines()) + "\n" + text
    write_text_atomic(path, text)
