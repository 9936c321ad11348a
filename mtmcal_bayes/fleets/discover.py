"""Finding a fleet's campaigns: every campaign TOML under a folder, fingerprinted and grouped by machine.

Every ``*.toml`` under the folder (recursively, in sorted order of its path; hidden files and folders, and the
run's own output and cache folders, skipped) is read with :func:`~mtmcal_bayes.io.load_campaign`.  A file that
does not load is an error of the fleet (its one-line message), never the end of the run.  Each campaign is
fingerprinted by its *content*: the bytes of the file and of the files it names (ball-bar traces, DPRNT
output), not its name or place; the fingerprint seeds its work and names its cache entry.

Campaigns are grouped by ``[machine] serial``.  A campaign without a serial cannot be matched with any other:
it is a machine of its own, known by its file.  Machines may be of any type and description (the thesis machine,
described machines); a serial whose campaigns are on two different descriptions is an error of the fleet naming
its files (:mod:`~mtmcal_bayes.io.machine_identity`), and the other machines are computed.  A machine's campaigns
are in date order (a missing date sorts after every dated campaign, those in file order); only dated campaigns
make its history.
"""

from __future__ import annotations

import datetime
import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path

from ..campaign import Campaign
from ..errors import InputError, MtmcalError
from ..io import load_campaign
from ..io.machine_identity import description_key, description_label


@dataclass
class CampaignFile:
    """One campaign of the fleet: where it was found, what it holds, and the fingerprint of its content."""

    file: str  # the path as found (the folder as given joined with the path below it)
    campaign: Campaign
    digest: str  # sha256 of the file's bytes and of every file it names

    @property
    def date_text(self) -> str | None:
        d = self.campaign.date
        if d is None:
            return None
        return d.date().isoformat() if d.time() == datetime.time(0) and d.tzinfo is None else d.isoformat()


@dataclass
class Machine:
    """The campaigns of one machine: dated ones by date, then undated ones in file order."""

    serial: str | None
    id: str  # the serial, or "file:<path below the folder>" for a campaign without one
    campaigns: list[CampaignFile] = field(default_factory=list)

    @property
    def dated(self) -> list[CampaignFile]:
        return [c for c in self.campaigns if c.campaign.date is not None]

    @property
    def type(self) -> str:
        """The machine's ``[machine] type`` (its latest campaign's; "" when not given)."""
        return self.latest.machine.type

    @property
    def latest(self) -> Campaign:
        """Its latest campaign (dated ones first)."""
        return (self.dated or self.campaigns)[-1].campaign


def check_types(found: Discovery) -> None:
    """Machines of one ``[machine] type`` share a σ_model hyper-distribution, so they must be one make and model:
    the same description (:func:`~mtmcal_bayes.io.machine_identity.description_key`), configuration and axis
    travels.  Otherwise an :class:`~mtmcal_bayes.errors.InputError` naming the file and ``machine.type``."""
    from .sigma_model import geometry

    first: dict[str, tuple] = {}
    for m in found.machines:
        for cf in m.campaigns:
            t = cf.campaign.machine.type
            if not t:
                continue
            g = geometry(cf.campaign.machine)
            if t not in first:
                first[t] = (g, cf.file)
            elif first[t][0] != g:
                raise InputError(cf.file, "machine.type", f"{t!r} is also the type of {first[t][1]}, whose machine has "
                                 "another description, configuration or other travels; one type is one make "
                                 "and model "
                                 "(machines of a type share their σ_model)")


@dataclass
class Discovery:
    """What a folder holds: machines (sorted by id, those without a serial last) and files that did not load."""

    directory: str
    machines: list[Machine]
    errors: list[dict]  # {"file", "message"}

    @property
    def n_campaigns(self) -> int:
        return sum(len(m.campaigns) for m in self.machines)


def _referenced(campaign: Campaign) -> list[Path]:
    """The files a campaign names (traces, DPRNT output), resolved as the reader resolved them."""
    names = [n for run in campaign.ballbar.runs for n in (run.trace_csv or [])]
    if campaign.probe is not None:
        names += campaign.probe.dprnt_files()
    base = campaign.base_dir
    return [Path(n) if base is None or os.path.isabs(n) else base / n for n in names]


def content_digest(path: Path, campaign: Campaign) -> str:
    """sha256 of the campaign file's bytes and of each file it names (its name as written, then its bytes)."""
    h = hashlib.sha256(b"mtmcal-campaign\0")
    h.update(path.read_bytes())
    for ref in _referenced(campaign):
        h.update(b"\0" + ref.name.encode("utf-8") + b"\0")
        h.update(ref.read_bytes() if ref.is_file() else b"<missing>")
    return h.hexdigest()


def _date_key(d: datetime.datetime) -> datetime.datetime:
    """A sort key for dates with and without a UTC offset (a date without one is taken as UTC)."""
    return d.replace(tzinfo=None) - (d.utcoffset() or datetime.timedelta(0))


def _inside(path: Path, folders: list[Path]) -> bool:
    return any(f == path or f in path.parents for f in folders)


def campaign_paths(directory: str | os.PathLike, skip=()) -> list[Path]:
    """Every ``*.toml`` below ``directory``, sorted by its path below it; hidden entries and ``skip`` folders left out."""
    root = Path(directory)
    if not root.exists():
        raise InputError(str(root), None, "folder not found")
    if not root.is_dir():
        raise InputError(str(root), None, "is a file, not a folder of campaigns")
    skipped = [Path(s).resolve() for s in skip if s is not None]
    found = []
    for p in root.rglob("*.toml"):
        rel = p.relative_to(root)
        if any(part.startswith(".") for part in rel.parts) or _inside(p.resolve(), skipped) or not p.is_file():
            continue
        found.append(p)
    return sorted(found, key=lambda p: p.relative_to(root).as_posix())


def _two_descriptions(m: Machine) -> dict:
    """The fleet's error for a serial whose campaigns are on different descriptions: one line naming the files of
    each description."""
    by: dict[tuple[str, str], list[str]] = {}
    for c in m.campaigns:
        machine = c.campaign.machine
        by.setdefault((description_key(machine), description_label(machine)), []).append(c.file)
    each = "; ".join(f"{', '.join(files)}: {label}" for (_, label), files in by.items())
    return {"file": None, "machine": m.id, "message": f"machine {m.id}: its campaigns describe {len(by)} different "
            f"machines ({each}); one serial is one machine, on one description"}


def discover(directory: str | os.PathLike, skip=()) -> Discovery:
    """Load every campaign below ``directory`` (see the module's description); ``skip``: folders to leave out."""
    root = Path(directory)
    loaded: list[CampaignFile] = []
    errors: list[dict] = []
    for path in campaign_paths(root, skip):
        try:
            c = load_campaign(path)
            c.require_measured_runs()  # a campaign designed but not yet measured has nothing to analyse
            loaded.append(CampaignFile(str(path), c, content_digest(path, c)))
        except MtmcalError as exc:
            errors.append({"file": str(path), "message": str(exc)})
        except (OSError, ValueError) as exc:  # unreadable between listing and reading, or not a campaign at all
            errors.append({"file": str(path), "message": f"{path}: {type(exc).__name__}: {exc}"})
    machines: dict[str, Machine] = {}
    for cf in loaded:
        serial = cf.campaign.machine.serial or None
        key = serial if serial is not None else f"file:{Path(cf.file).relative_to(root).as_posix()}"
        machines.setdefault(key, Machine(serial, key)).campaigns.append(cf)
    for m in machines.values():
        m.campaigns = (sorted(m.dated, key=lambda c: (_date_key(c.campaign.date), c.file))
                       + [c for c in m.campaigns if c.campaign.date is None])
    for key in [k for k, m in machines.items() if len({description_key(c.campaign.machine) for c in m.campaigns}) > 1]:
        errors.append(_two_descriptions(machines.pop(key)))  # which is the machine? say so, never guess
    order = sorted(machines.values(), key=lambda m: (m.serial is None, m.id))
    return Discovery(str(root), order, errors)
