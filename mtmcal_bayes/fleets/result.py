"""The result of a fleet: machines with their campaigns and histories, the errors, how the run went.

``to_json()`` holds the results (``machines``, ``errors``: the same for the same files and settings, whatever
the cluster, the number of workers or the cache) apart from ``run`` (timings, what came from the cache,
where it ran) and ``files`` (what was written).
"""

from __future__ import annotations

import base64
import os
import re
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from ..version import __version__
from .discover import Discovery, Machine
from .overview import machine_page, overview_page, summary_table, text_overview
from .units import FleetSettings

#: exit status of a fleet with failed campaigns or histories (the rest completed)
PARTIAL = 3


def slug(text: str) -> str:
    """A folder name for a machine: letters, digits, ``. _ -``; anything else ``_``."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", text).strip("._") or "machine"


def _unique_slugs(ids: list[str]) -> dict[str, str]:
    out, used = {}, set()
    for i in ids:
        s = slug(i.removeprefix("file:") if i.startswith("file:") else i)
        s = f"file-{s}" if i.startswith("file:") else s
        base, n = s, 2
        while s.lower() in used:  # case-insensitive file systems too
            s, n = f"{base}-{n}", n + 1
        used.add(s.lower())
        out[i] = s
    return out


def _latest(campaigns: list[dict], history: dict | None) -> dict:
    """Per quantity of the latest campaign with a posterior: mean, sd, HDI, unit, conformity, and from the
    history its drift flag (a change found) and its recalibrate-by date."""
    if not campaigns:
        return {}
    last = campaigns[-1]
    dated = [c for c in campaigns if c["date"] is not None]
    if dated:
        last = dated[-1]
    out = {}
    changes = (history or {}).get("changes") or []
    forecast = {f["quantity"]: f for f in (history or {}).get("forecast") or [] if isinstance(f, dict)}
    for q, s in last["summary"].items():
        entry = {k: s.get(k) for k in ("mean", "sd", "hdi_low", "hdi_high", "unit")}
        entry.update({"file": last["file"], "date": last["date"], "conformity": s.get("conformity"),
                      "p_nonconformance": s.get("p_nonconformance")})
        mine = [c for c in changes if isinstance(c, dict) and c.get("quantity") == q]
        entry["drift"] = bool(mine)
        entry["drift_date"] = mine[-1].get("date") if mine else None
        entry["drift_probability"] = mine[-1].get("probability") if mine else None
        entry["recalibrate_by"] = forecast.get(q, {}).get("recalibrate_by")
        out[q] = entry
    return out


@dataclass
class FleetResult:
    """A fleet's machines (``serial``, ``id``, ``campaigns``, ``history``, ``changes``, ``forecast``,
    ``latest``, ``page``, ``notes``), its ``errors`` (``file``, ``message``; ``machine`` for a history) and
    ``run``: units, how many came from the cache, failed, workers, times.  ``exit_status`` is 0 when
    everything ran, 3 when something failed and the rest completed."""

    directory: str
    settings: FleetSettings
    machines: list[dict]
    errors: list[dict]
    run: dict
    pages: dict[str, dict[str, str]] = field(default_factory=dict)  # machine id -> {path: base64} of its history page
    files: list[str] = field(default_factory=list)  # what :meth:`write` wrote

    @property
    def exit_status(self) -> int:
        return PARTIAL if self.errors else 0

    @classmethod
    def assemble(cls, found: Discovery, settings: FleetSettings, *, payloads: dict, cached: set, of_file: dict,
                 of_machine: dict, run: dict) -> FleetResult:
        """The result from a discovery and the payloads of its units (see :mod:`~mtmcal_bayes.fleets.run`)."""
        errors = list(found.errors)
        machines, pages = [], {}
        cached_files, cached_machines = [], []
        slugs = _unique_slugs([m.id for m in found.machines])
        for m in found.machines:
            entry, page = cls._machine(m, payloads, of_file=of_file, of_machine=of_machine, errors=errors)
            entry["page"] = f"machines/{slugs[m.id]}/index.html"
            machines.append(entry)
            if page:
                pages[m.id] = page
            cached_files += [c.file for c in m.campaigns if of_file[c.file] in cached]
            if m.id in of_machine and of_machine[m.id] in cached:
                cached_machines.append(m.id)
        errors.sort(key=lambda e: (e.get("file") or "", e.get("machine") or ""))
        run = {**run, "cached_campaigns": cached_files, "cached_histories": cached_machines}
        return cls(found.directory, settings, machines, errors, run, pages)

    @staticmethod
    def _machine(m: Machine, payloads, *, of_file, of_machine, errors: list) -> tuple[dict, dict]:
        campaigns, notes = [], []
        for cf in m.campaigns:
            p = payloads[of_file[cf.file]]
            if "error" in p:
                errors.append({"file": cf.file, "message": p["error"]})
                notes.append(f"{cf.file}: no posterior ({p['error']})")
                continue
            campaigns.append({"file": cf.file, "date": cf.date_text, "temperature_C": cf.campaign.temperature_C,
                              **p["result"]})
        undated = [c.file for c in m.campaigns if c.campaign.date is None]
        if undated and len(m.campaigns) > 1:
            notes.append(f"{len(undated)} campaign(s) without a date, not in the history: {', '.join(undated)}")
        if m.serial is None:
            notes.append("no [machine] serial: a machine of its own, known by its file")
        history, page = None, {}
        if m.id in of_machine:
            p = payloads[of_machine[m.id]]
            if "error" in p:
                errors.append({"file": None, "machine": m.id, "message": f"history of {m.id}: {p['error']}"})
            else:
                history, page = p["result"], p["files"]
        elif len(m.campaigns) > 1 and len(m.dated) < 2:
            notes.append("no history: it needs at least two dated campaigns")
        entry = {"serial": m.serial, "id": m.id, "campaigns": campaigns,
                 "history": None if history is None else {
                     "model": history.get("model"), "dates": history.get("dates"), "files": [c.file for c in m.dated],
                     "summary": history.get("summary"), "diagnostics": history.get("diagnostics")},
                 "changes": (history or {}).get("changes") or [], "forecast": (history or {}).get("forecast") or [],
                 "latest": _latest(campaigns, history), "notes": notes}
        return entry, page

    # ------------------------------------------------------------------ outputs
    def to_json(self) -> dict:
        """What ``fleet --json`` prints and ``fleet.json`` holds."""
        return {"directory": self.directory, "settings": {**self.settings.to_json(), "version": __version__},
                "machines": self.machines, "errors": self.errors, "run": self.run, "files": self.files}

    def results_json(self) -> dict:
        """The part of :meth:`to_json` that depends only on the files and the settings: ``machines``, ``errors``."""
        return {"machines": self.machines, "errors": self.errors}

    def to_text(self) -> str:
        """What ``fleet`` prints: one line per machine with its flags, the errors, how the run went."""
        return text_overview(self)

    def write(self, output: str | os.PathLike) -> list[str]:
        """Write ``fleet.json``, ``fleet_summary.csv``, ``index.html`` and ``machines/<id>/`` into ``output``
        (created if needed), all at once: a failure leaves what was there before."""
        from ..io.json_text import json_text
        from ..io.textfiles import atomic_directory

        out = Path(output)
        names = ["index.html", "fleet.json", "fleet_summary.csv"]
        self.files = [str(out / n) for n in names] + [str(out / m["page"]) for m in self.machines]
        old = None
        with atomic_directory(out) as tmp:
            for m in self.machines:
                folder = tmp / Path(m["page"]).parent
                folder.mkdir(parents=True)
                for rel, data in self.pages.get(m["id"], {}).items():
                    (folder / rel).parent.mkdir(parents=True, exist_ok=True)
                    (folder / rel).write_bytes(base64.b64decode(data))
                if (folder / "history.json").exists():  # as the history wrote it, with the files and folder of this run
                    doc = {"serial": m["serial"], **m["history"], "changes": m["changes"], "forecast": m["forecast"],
                           "output": str(out / Path(m["page"]).parent)}
                    (folder / "history.json").write_text(json_text(doc) + "\n", encoding="utf-8")
                own = "index.html" if not (folder / "index.html").exists() else "campaigns.html"
                machine_page(self, m).write(folder / own, f"mtmcal-bayes {__version__}")
            overview_page(self).write(tmp / "index.html", f"mtmcal-bayes {__version__}")
            summary_table(self).to_csv(tmp / "fleet_summary.csv", index=False)
            (tmp / "fleet.json").write_text(json_text(self.to_json()) + "\n", encoding="utf-8")
            if (out / "machines").exists():  # a folder is not replaced by os.replace: set the old one aside
                old = out / f".machines-old-{os.getpid()}"
                os.replace(out / "machines", old)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return self.files

