"""Running a fleet: discover the campaigns, load what the cache has, compute the rest on Dask, assemble.

Work units (:mod:`~mtmcal_bayes.fleets.units`): one per distinct campaign content (its posterior) and one per
machine with at least two dated campaigns (its history).  Units already in the cache are loaded; the others
are submitted together to a Dask cluster (:func:`~mtmcal_bayes.cluster.dask_client`: a local one of at most
one worker per unit, or the scheduler given) and collected as they finish, each cached at once.  No cluster
is started when everything is cached.
"""

from __future__ import annotations

import contextlib
import functools
import time
import warnings
from dataclasses import dataclass

from ..cluster import dask_client, default_workers, remembered_interrupt
from ..errors import ParameterError
from ..progress import Progress, ProgressEvent, emit
from .cache import UnitCache, default_cache
from .discover import Discovery, check_types, discover
from .result import FleetResult
from .units import FleetSettings, campaign_unit, history_unit, unit_key, unit_seed

TASK = "fleet"


@dataclass
class Unit:
    kind: str  # "campaign" or "history"
    key: str
    label: str  # what progress and errors name: a file or a machine
    func: object
    args: tuple


def plan_units(found: Discovery, settings: FleetSettings, *, pages: bool) -> tuple[list[Unit], dict, dict]:
    """The distinct units of a discovery (``pages``: the histories write their pages too);
    ``{file: campaign key}``, ``{machine id: history key}``."""
    units: dict[str, Unit] = {}
    of_file, of_machine = {}, {}
    for m in found.machines:
        for cf in m.campaigns:
            key = unit_key("campaign", [cf.digest], settings)
            of_file[cf.file] = key
            units.setdefault(key, Unit("campaign", key, cf.file, campaign_unit,
                                       (cf.campaign, settings, unit_seed([cf.digest], settings.seed))))
        dated = m.dated
        if len(dated) >= 2:
            digests = [c.digest for c in dated]
            key = unit_key("history", digests, settings)
            of_machine[m.id] = key
            # plant-wide (by this machine's names), or None
            func = functools.partial(history_unit, tolerances=settings.tolerances_for(dated[-1].campaign.machine)[0])
            units.setdefault(key, Unit("history", key, m.id, func,
                                       ([c.campaign for c in dated], unit_seed(digests, settings.seed), pages,
                                        settings.model)))
    return list(units.values()), of_file, of_machine


@contextlib.contextmanager
def _client(scheduler, workers):
    """:func:`~mtmcal_bayes.cluster.dask_client`, without the warning that port 8787 is busy (the scheduler's
    HTTP server moves to another port by itself: nothing a user must act on)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="Port .* is already in use", category=UserWarning)
        with dask_client(scheduler, workers) as client:
            yield client


def _compute(missing: list[Unit], store: UnitCache | None, *, scheduler, workers, report) -> dict:
    """Run ``missing`` on Dask; each result cached as it arrives.  Returns ``{key: payload}`` and cluster facts."""
    from distributed import as_completed

    n_local = min(workers or default_workers(), len(missing))
    out = {}
    with _client(scheduler, None if scheduler else n_local) as client:
        n_workers = len(client.scheduler_info().get("workers", {})) if scheduler else n_local
        report(f"computing {len(missing)} units on {n_workers} worker{'s' * (n_workers != 1)} "
               f"({'scheduler ' + str(scheduler) if scheduler else 'local cluster'})")
        futures = {client.submit(u.func, *u.args, key=f"mtmcal-fleet-{u.kind}-{u.key}", pure=False): u for u in missing}
        with remembered_interrupt() as interrupt:
            for fut in as_completed(futures):
                interrupt.check()
                u = futures[fut]
                try:
                    payload = fut.result()
                except Exception as exc:  # the worker died (KilledWorker) or the task could not run
                    payload = {"error": f"{u.label}: {type(exc).__name__}: {exc}".splitlines()[0], "elapsed_s": 0.0}
                if "error" not in payload and store is not None:
                    store.put(u.kind, u.key, payload)
                out[u.key] = payload
                report(f"{u.kind} {u.label}: {'FAILED' if 'error' in payload else 'done'} in "
                       f"{payload.get('elapsed_s', 0.0):.1f} s", done=True)
                fut.release()
            interrupt.check()
    return {"results": out, "workers": n_workers}


def run_fleet(directory, settings: FleetSettings, *, scheduler: str | None = None, workers: int | None = None,
              output=None, cache=None, progress: Progress | None = None) -> FleetResult:
    """Every machine's campaigns below ``directory``: posteriors and histories, from the cache or computed.

    ``cache``: the cache folder (default :func:`~mtmcal_bayes.fleets.cache.default_cache`), or ``False`` for
    none.  ``output``: the folder the overview will be written to (left out of the search).
    """
    t0 = time.perf_counter()
    if workers is not None and scheduler is not None:
        raise ParameterError("workers", "sets the size of a local cluster; a scheduler's cluster has its own workers")
    if workers is not None and (not isinstance(workers, int) or workers < 1):
        raise ParameterError("workers", f"{workers}: at least one worker is needed")
    folder = None if cache is False else (default_cache(output) if cache is None else cache)
    store = None if folder is None else UnitCache(folder)
    found = discover(directory, skip=[output, folder])
    check_types(found)
    for m in found.machines:  # two names of one quantity of a machine: the tolerance file's error, before any work
        settings.tolerances_for(m.latest.machine)
    if not found.machines and not found.errors:
        raise ParameterError("directory", f"{directory}: no campaign files (*.toml) below it")
    units, of_file, of_machine = plan_units(found, settings, pages=output is not None)
    payloads, cached = {}, set()
    for u in units:
        hit = store.get(u.kind, u.key) if store is not None else None
        if hit is not None and not (u.kind == "history" and output is not None and not hit["files"]):
            payloads[u.key] = hit
            cached.add(u.key)
    missing = [u for u in units if u.key not in payloads]
    n_done = [len(cached)]

    def report(message: str, done: bool = False) -> None:  # a finished unit is counted, anything else a stage
        elapsed = time.perf_counter() - t0
        if done:
            n_done[0] += 1
            message = f"{n_done[0]}/{len(units)} units ({message})"
        emit(progress, ProgressEvent(TASK, message, n_done[0] if done else None, len(units) if done else None, elapsed))

    report(f"{found.n_campaigns} campaigns of {len(found.machines)} machines below {directory}, "
           f"{len(found.errors)} unreadable; {len(units)} units, {len(cached)} in the cache")
    n_workers = 0
    if missing:
        computed = _compute(missing, store, scheduler=scheduler, workers=workers, report=report)
        payloads.update(computed["results"])
        n_workers = computed["workers"]
    run = {"units": len(units), "cached": len(cached), "computed": len(missing),
           "failed": sum("error" in payloads[u.key] for u in units),
           "cache": None if folder is None else str(folder), "scheduler": scheduler, "workers": n_workers,
           "wall_time_s": time.perf_counter() - t0,
           "compute_time_s": sum(payloads[u.key].get("elapsed_s", 0.0) for u in missing)}
    return FleetResult.assemble(found, settings, payloads=payloads, cached=cached, of_file=of_file,
                                of_machine=of_machine, run=run)
