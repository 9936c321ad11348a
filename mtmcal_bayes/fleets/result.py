"""The result of a fleet: machines with their campaigns and histories, the errors, how the run went.

``to_json()`` holds the results (``machines``, ``errors``: the same for the same files and settings, whatever
the cluster, the number of workers or the cache) apart from ``run`` (timings, what came from the cache,
where it ran) and ``files`` (what was written).
"""

from __future__ import annotations

import base64
import json
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from ..io.sigma_prior_file import write_sigma_model_prior
from ..machines.plugins import provided
from ..parameters import quantity_unit
from ..sigma_prior import SigmaModelPrior, log_sd_problem, median_problem
from ..version import __version__
from .discover import Discovery, Machine
from .overview import campaign_anchor, campaigns_page, machine_page, overview_page, summary_table, text_overview
from .sigma_model import pool
from .tolerances import display_limits, estimate_conformity
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


#: what a machine's ``latest`` keeps of the campaign beside the history's estimate
_CAMPAIGN_KEYS = ("mean", "sd", "hdi_low", "hdi_high", "conformity", "p_nonconformance")


def _latest(campaigns: list[dict], history: dict | None, *, history_file: str | None, limits: dict,
            page: str) -> dict:
    """Per quantity, the latest estimate of the machine: the history's at its latest date where the machine has a
    history (at 20 °C where it modelled the temperatures; ``"source": "history"``; conformity decided on that estimate taken as normal, with ``limits``
    ``{name: {"low", "high"}}`` display units: :func:`~.tolerances.estimate_conformity`), else the latest
    campaign's posterior (``"source": "campaign"``, its own verdict); always with the single campaign's posterior
    of that date (``"campaign"``, its section on ``page`` linked), the history's drift flag (a change found) and
    its recalibrate-by date."""
    dated = [c for c in campaigns if c["date"] is not None]
    fallback = (dated or campaigns or [None])[-1]  # the latest campaign with a posterior, dated ones first
    at = history["dates"][-1] if history and history.get("dates") else None
    # at 20 °C where the history modelled the temperatures (ISO 1: results are referred to 20 °C)
    now = ((history.get("summary_20C") or history.get("summary") or {}).get(at) or {}) if at else {}
    same = next((c for c in campaigns if c["file"] == history_file), None) if at else fallback
    names = list(fallback["summary"] if fallback else {})
    names += [q for q in now if q not in names]
    changes = (history or {}).get("changes") or []
    forecast = {f["quantity"]: f for f in (history or {}).get("forecast") or [] if isinstance(f, dict)}

    def single(c: dict | None, q: str) -> dict | None:  # the campaign's own posterior of q, its section linked
        own = None if c is None else c["summary"].get(q)
        if own is None:
            return None
        return {"file": c["file"], "date": c["date"], **{k: own.get(k) for k in _CAMPAIGN_KEYS},
                "page": f"{page}#{campaign_anchor(campaigns.index(c))}"}

    out = {}
    for q in names:
        if q in now:
            entry = {k: now[q].get(k) for k in ("mean", "sd", "hdi_low", "hdi_high")}
            entry.update({"unit": quantity_unit(q), "file": history_file, "date": at, "conformity": None,
                          "p_nonconformance": None})
            tol = limits.get(q)
            if tol is not None and entry["mean"] is not None and entry["sd"] is not None:
                entry["conformity"], entry["p_nonconformance"] = estimate_conformity(
                    entry["mean"], entry["sd"], tol["low"], tol["high"])
            source, camp = "history", single(same, q)
        else:
            own = fallback["summary"][q]
            entry = {k: own.get(k) for k in ("mean", "sd", "hdi_low", "hdi_high", "unit")}
            entry.update({"file": fallback["file"], "date": fallback["date"], "conformity": own.get("conformity"),
                          "p_nonconformance": own.get("p_nonconformance")})
            tol, source, camp = own.get("tolerance"), "campaign", single(fallback, q)
        mine = [c for c in changes if isinstance(c, dict) and c.get("quantity") == q]
        entry["drift"] = bool(mine)
        entry["drift_date"] = mine[-1].get("date") if mine else None
        entry["drift_probability"] = mine[-1].get("probability") if mine else None
        entry["recalibrate_by"] = forecast.get(q, {}).get("recalibrate_by")
        entry.update({"source": source, "tolerance": tol, "campaign": camp})
        out[q] = entry
    return out


def machine_identity(m: Machine) -> dict:
    """What the overview names of a machine: ``type`` (its ``[machine] type``: whose σ_model it pools with),
    ``configuration``, ``description`` (the thesis machine, a built-in type's name, or "described <configuration>")
    and, where its plug-ins state no quantities of their own to report (the thesis': Table 4.5's eight, the
    overview's first columns), ``deviations`` (its description's, ISO 230-7 name -> meaning)."""
    from ..io.machine_identity import description_label

    machine = m.latest.machine
    out = {"type": machine.type, "configuration": machine.configuration, "description": description_label(machine)}
    if provided(machine, "reported_quantities") is None:
        from ..machines.selection import selected

        out["deviations"] = {d.name: d.meaning for d in selected(machine.description)}
    return out


def _not_determined(entry: dict, history: dict | None) -> list[dict]:
    """A described machine's deviations that are not shown as measured, with why: its history's list, else those
    its latest campaign does not determine one by one (the Jacobian's statement; ``latest`` loses them)."""
    if history is not None and history.get("not_determined") is not None:
        left = list(history["not_determined"])
    else:
        last = (entry["campaigns"] or [None])[-1]
        left = [{"quantity": q, "why": f"not determined one by one by the campaign ({s.get('identification')})"}
                for q, s in ((last or {}).get("summary") or {}).items() if s.get("identified") is False]
    hidden = {x["quantity"] for x in left}
    for q in hidden:
        entry["latest"].pop(q, None)
    return left


def pooled_types(found: Discovery, machines: list[dict], payloads: dict, of_machine: dict) -> dict:
    """Per machine type shared by two or more machines: σ_model pooled over their histories (:mod:`.sigma_model`);
    each machine entry of the type gets it as ``"sigma_model"`` (None for the others)."""
    by_type: dict[str, list[int]] = {}
    for i, m in enumerate(found.machines):
        if m.type:
            by_type.setdefault(m.type, []).append(i)
    out = {}
    for name, members in sorted(by_type.items()):
        rows = [payloads[of_machine[found.machines[i].id]]["result"].get("sigma_model_loglik") for i in members
                if found.machines[i].id in of_machine and "error" not in payloads[of_machine[found.machines[i].id]]]
        rows = [r for r in rows if r is not None]
        if len(members) < 2 or not rows:
            continue
        pooled = pool(rows)
        # a predictive wider than a prior file may say (ln σ sd > 3: a factor 20 per sd) has learnt nothing to pass on
        usable = median_problem(pooled["median_um"]) is None and log_sd_problem(pooled["log_sd"]) is None
        out[name] = {"type": name, "machines": len(members), **pooled,
                     "prior_file": f"sigma_model_{slug(name)}.toml" if usable else None}
    for i, m in enumerate(found.machines):
        machines[i]["sigma_model"] = out.get(m.type) if m.type else None
    return out


def learnt_prior(pooled: dict, directory: str) -> SigmaModelPrior:
    """The ``sample --sigma-model-prior`` file of a pooled type."""
    return SigmaModelPrior({"sigma_model": (pooled["median_um"], pooled["log_sd"])},
                           f"fleet {directory}: type {pooled['type']!r}, {pooled['machines']} machines, "
                           f"{pooled['histories']} histories (τ = {pooled['tau']['mean']:.2f} ± {pooled['tau']['sd']:.2f} "
                           "in ln σ between machines)")


@dataclass
class FleetResult:
    """A fleet's machines (``serial``, ``id``, ``campaigns``, ``history``, ``changes``, ``forecast``,
    ``latest``, ``sigma_model``, ``page``, ``notes``), the σ_model each machine type's histories taught
    (``types``, :mod:`.sigma_model`), its ``errors`` (``file``, ``message``; ``machine`` for a history) and
    ``run``: units, how many came from the cache, failed, workers, times.  ``exit_status`` is 0 when
    everything ran, 3 when something failed and the rest completed."""

    directory: str
    settings: FleetSettings
    machines: list[dict]
    errors: list[dict]
    run: dict
    pages: dict[str, dict[str, str]] = field(default_factory=dict)  # machine id -> {path: base64} of its history page
    types: dict[str, dict] = field(default_factory=dict)  # machine type -> σ_model pooled by its histories
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
            entry, files = cls._machine(m, payloads, of_file=of_file, of_machine=of_machine, errors=errors,
                                        settings=settings, page=f"machines/{slugs[m.id]}/index.html")
            machines.append(entry)
            if files:
                pages[m.id] = files
            cached_files += [c.file for c in m.campaigns if of_file[c.file] in cached]
            if m.id in of_machine and of_machine[m.id] in cached:
                cached_machines.append(m.id)
        errors.sort(key=lambda e: (e.get("file") or "", e.get("machine") or ""))
        run = {**run, "cached_campaigns": cached_files, "cached_histories": cached_machines}
        types = pooled_types(found, machines, payloads, of_machine)
        return cls(found.directory, settings, machines, errors, run, pages, types)

    @staticmethod
    def _machine(m: Machine, payloads, *, of_file, of_machine, errors: list, settings: FleetSettings,
                 page: str) -> tuple[dict, dict]:
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
        history, files = None, {}
        if m.id in of_machine:
            p = payloads[of_machine[m.id]]
            if "error" in p:
                errors.append({"file": None, "machine": m.id, "message": f"history of {m.id}: {p['error']}"})
            else:
                history, files = p["result"], p["files"]
        elif len(m.campaigns) > 1 and len(m.dated) < 2:
            notes.append("no history: it needs at least two dated campaigns")
        entry = {"serial": m.serial, "id": m.id, **machine_identity(m), "campaigns": campaigns,
                 "history": None if history is None else {
                     "model": history.get("model"), "dates": history.get("dates"), "files": [c.file for c in m.dated],
                     "summary": history.get("summary"), "diagnostics": history.get("diagnostics"),
                     **({"summary_20C": history["summary_20C"]} if history.get("summary_20C") else {})},
                 "changes": (history or {}).get("changes") or [], "forecast": (history or {}).get("forecast") or [],
                 "latest": {}, "notes": notes, "page": page}
        # the history's tolerances: the plant-wide set, else its latest campaign's own (as its forecast's)
        plant, not_here = settings.tolerances_for((m.dated[-1].campaign if m.dated else m.latest).machine)
        limits = display_limits(plant if plant is not None else m.dated[-1].campaign.tolerances if m.dated else {})
        if not_here:  # said, not left blank without a word (and never "conforms")
            notes.append(f"no verdict on {', '.join(not_here)}: the plant-wide tolerances name quantities this "
                         "machine does not have")
            entry["tolerances_not_here"] = not_here
        entry["latest"] = _latest(campaigns, history, history_file=m.dated[-1].file if history else None,
                                  limits=limits, page=campaigns_page(entry))
        entry["not_determined"] = _not_determined(entry, history)
        return entry, files

    # ------------------------------------------------------------------ outputs
    def to_json(self) -> dict:
        """What ``fleet --json`` prints and ``fleet.json`` holds."""
        return {"directory": self.directory, "settings": {**self.settings.to_json(), "version": __version__},
                "machines": self.machines, "errors": self.errors, "sigma_model_types": self.types, "run": self.run,
                "files": self.files}

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
        names = ["index.html", "fleet.json", "fleet_summary.csv"] + [t["prior_file"] for t in self.types.values()
                                                                     if t["prior_file"]]
        self.files = [str(out / n) for n in names] + [str(out / m["page"]) for m in self.machines]
        with atomic_directory(out) as tmp:  # machines/ replaced whole: no page of an earlier run is left beside these
            for m in self.machines:
                folder = tmp / Path(m["page"]).parent
                folder.mkdir(parents=True)
                for rel, data in self.pages.get(m["id"], {}).items():
                    (folder / rel).parent.mkdir(parents=True, exist_ok=True)
                    (folder / rel).write_bytes(base64.b64decode(data))
                if (folder / "history.json").exists():  # as the history wrote it, with the files and folder of this run
                    doc = json.loads((folder / "history.json").read_text(encoding="utf-8"))
                    doc.update(files=m["history"]["files"], output=str(out / Path(m["page"]).parent))
                    (folder / "history.json").write_text(json_text(doc) + "\n", encoding="utf-8")
                own = [Path(campaigns_page(m)).name] + ["index.html"] * (not (folder / "index.html").exists())
                for name in dict.fromkeys(own):  # campaigns.html beside a history page; index.html if none
                    machine_page(self, m).write(folder / name, f"mtmcal-bayes {__version__}")
            overview_page(self).write(tmp / "index.html", f"mtmcal-bayes {__version__}")
            summary_table(self).to_csv(tmp / "fleet_summary.csv", index=False)
            for t in self.types.values():
                if t["prior_file"]:
                    write_sigma_model_prior(tmp / t["prior_file"], learnt_prior(t, self.directory))
            (tmp / "fleet.json").write_text(json_text(self.to_json()) + "\n", encoding="utf-8")
        return self.files

