"""σ_model learnt by a fleet: do a new machine's 90 % intervals under the learnt prior cover 90 %?

    python bench/fleet_sigma.py [--fleets 200] [--machines 4] [--campaigns 4] [--workers 2] [--quick]
                                [--seed 20250106] [-o bench_fleet_sigma.json]

Simulated machine types (the thesis campaign as the base, ``model="linear"``, no drift).  A *fleet* is
``--machines`` machines of one type, each with a history of ``--campaigns`` quarterly campaigns
(``synthetic_history``: deviations drawn from their priors, set-up offsets fresh each campaign, a model
discrepancy σ_model of its own drawn fresh for each observation of each campaign).  Each history's likelihood of
(ln κ, ln σ) is ``history_log_likelihood`` of its ``HistoryModel`` (exact, no sampler; the fleet command computes
the same from the history it fits, with the trends that fit chose — a history without drift has none to
choose), pooled by ``pool`` into a new machine's log-normal prior (``learnt_prior``).

Every fleet teaches one *new machine*: one campaign from the same simulator, its whole truth (deviations,
set-up and mount offsets) drawn from the campaign's priors, its σ_model set by the row.  Its posterior is the
exact linear-Gaussian posterior with σ_model marginalised on a grid (``ExactDraws``: independent draws, the
engine of ``sample --sampler exact``) under the learnt prior and under the assumed one (half-normal 2 µm); per
quantity of ``IDENTIFIABLE``, whether the truth lies in the central 90 % interval, and the interval's width.

Rows (``--fleets`` fleets each, every fleet simulated afresh):

* **shared σ** (the acceptance rows): the fleet's machines and the new machine at σ_model 0.5, 1, 2 and 4 µm;
* **new 3× fleet** (secondary): the 1 µm fleets teach a new machine at 3 µm (the learnt prior misleads);
* **fleet differs** (secondary): fleets of three machines at 0.5, 1.5 and 4 µm, a new machine at 1.5 µm.

Coverage of the 90 % intervals, for each row and prior:

* **pooled** over the eight quantities, ``k / (8·F)``.  The eight indicators of one new machine share its data
  and its fleet's prior, so they are not independent; fleets are.  Its 95 % interval is Clopper–Pearson on the
  effective number of independent indicators (``8·F / deff``, the design effect ``deff`` measured from the
  spread of the per-fleet coverages: Korn & Graubard 1998), beside a percentile bootstrap over fleets.
* **per quantity**, ``k / F``: one indicator per fleet, independent across fleets, so Clopper–Pearson is exact.

Every fleet's seeds come from ``numpy.random.SeedSequence(--seed, spawn_key=(row, fleet))``: fleet *f* of a row is
the same whatever the worker count or ``--fleets``.  The fleets run in ``--workers`` single-threaded processes.
Prints Markdown tables; writes the numbers and every fleet's record to ``-o``.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):  # one BLAS thread per worker
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import datetime  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
import warnings  # noqa: E402
from concurrent.futures import ProcessPoolExecutor  # noqa: E402
from functools import lru_cache  # noqa: E402

import numpy as np  # noqa: E402
from scipy import stats  # noqa: E402

#: name, the σ_model of the fleet's machines (µm), the new machine's σ_model (µm), acceptance row?
ROWS = (
    ("shared 0.5", (0.5,), 0.5, True),
    ("shared 1", (1.0,), 1.0, True),
    ("shared 2", (2.0,), 2.0, True),
    ("shared 4", (4.0,), 4.0, True),
    ("new 3× fleet", (1.0,), 3.0, False),
    ("fleet differs", (0.5, 1.5, 4.0), 1.5, False),
)
PRIORS = ("assumed", "learnt")
LEVEL = 0.90
N_DRAWS = 4000
BAND = (0.88, 0.92)
BOOTSTRAP = 4000


@lru_cache(maxsize=1)
def _base():
    """The thesis campaign and its linear posterior structure (once per worker process)."""
    import mtmcal_bayes as mb
    from mtmcal_bayes.inference.log_posterior import LogPosterior

    base = mb.load_campaign()
    return base, LogPosterior(base, "linear")


def _truth(rng: np.random.Generator):
    """A whole truth drawn from the campaign's priors (deviations, set-up and mount offsets); σ_model not drawn."""
    from mtmcal_bayes.simulation.simulate import truth_from_vector

    base, post = _base()
    return truth_from_vector(post.space, post.priors.rvs(1, rng)[0][: post.p])


def learn(sigmas_um, n_machines: int, n_campaigns: int, rng: np.random.Generator) -> dict:
    """One fleet: ``n_machines`` histories (machine k at ``sigmas_um[k % len]``), pooled; returns the pool."""
    from mtmcal_bayes import units
    from mtmcal_bayes.campaign import Truth
    from mtmcal_bayes.fleets.sigma_model import history_log_likelihood, pool
    from mtmcal_bayes.histories.model import HistoryModel
    from mtmcal_bayes.simulation.history import synthetic_history

    base, _ = _base()
    dates = [datetime.datetime(2025, 1, 6) + datetime.timedelta(days=91 * i) for i in range(n_campaigns)]
    tables = []
    for k in range(n_machines):
        truth = Truth(dict(_truth(rng).deviations))  # set-up offsets: synthetic_history draws them per campaign
        camps = synthetic_history(base, truth, dates, serial=f"F-{k + 1}", seed=int(rng.integers(2**31)),
                                  sigma_model=units.to_internal(sigmas_um[k % len(sigmas_um)], "um"))
        tables.append(history_log_likelihood(HistoryModel(camps)))
    return {"type": "SIM", "machines": n_machines, **pool(tables)}


def new_machine(sigma_um: float, prior, rng: np.random.Generator) -> dict:
    """A new machine's single campaign at ``sigma_um``: per prior, the truth in the central 90 % interval of each
    identifiable quantity ``(8,)`` and the interval's width ``(8,)`` (display units)."""
    from mtmcal_bayes import units
    from mtmcal_bayes.inference.log_posterior import LogPosterior
    from mtmcal_bayes.parameters import IDENTIFIABLE
    from mtmcal_bayes.simulation.simulate import synthetic_campaign, truth_vector
    from mtmcal_bayes.validation.samplers import ExactDraws
    from mtmcal_bayes.validation.sbc import quantity_values

    base, _ = _base()
    truth = _truth(rng)
    c = synthetic_campaign(base, truth, "linear", noise=True, seed=int(rng.integers(2**31)),
                           sigma_model=units.to_internal(sigma_um, "um"))
    k = len(IDENTIFIABLE)
    out = {}
    for name, p in zip(PRIORS, (None, prior)):
        post = LogPosterior(c, "linear", sigma_prior=p)
        draws = ExactDraws(n_all=N_DRAWS)(post, 0, rng).all
        q = quantity_values(post, draws)[:, :k]
        t = quantity_values(post, np.append(truth_vector(post.space, truth), 0.0)[None])[0, :k]
        lo, hi = np.quantile(q, [(1 - LEVEL) / 2, (1 + LEVEL) / 2], axis=0)
        out[name] = {"inside": ((lo <= t) & (t <= hi)).tolist(), "width": (hi - lo).tolist(),
                     "sigma_median_um": float(units.from_internal(np.median(draws[:, post.p]), "um"))}
    return out


def one_fleet(task: tuple) -> dict:
    """Row ``r``, fleet ``f``: learn, then a new machine (runs in a worker)."""
    from mtmcal_bayes.fleets.result import learnt_prior

    r, f, root, n_machines, n_campaigns = task
    name, fleet_um, new_um, _ = ROWS[r]
    rng = np.random.default_rng(np.random.SeedSequence(root, spawn_key=(r, f)))
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        machines = n_machines if len(fleet_um) == 1 else len(fleet_um)
        pooled = learn(fleet_um, machines, n_campaigns, rng)
        rec = new_machine(new_um, learnt_prior(pooled, "bench/fleet_sigma.py simulated fleet"), rng)
    return {"row": r, "fleet": f, "pooled": pooled, **rec, "seconds": time.perf_counter() - t0}


def cp(k: int, n: int) -> tuple[float, float]:
    """Clopper–Pearson (exact) 95 % interval of a binomial share."""
    ci = stats.binomtest(int(k), int(n)).proportion_ci(confidence_level=0.95, method="exact")
    return float(ci.low), float(ci.high)


def pooled_coverage(inside: np.ndarray, rng: np.random.Generator) -> dict:
    """Coverage pooled over quantities from ``inside`` (F fleets, Q quantities): the share, the design effect of the
    clusters (fleets), Clopper–Pearson on the effective sample size, and a percentile bootstrap over fleets."""
    F, Q = inside.shape
    share = float(inside.mean())
    per_fleet = inside.mean(axis=1)
    binom_var = share * (1 - share) / (F * Q)
    cluster_var = per_fleet.var(ddof=1) / F if F > 1 else binom_var
    deff = max(1.0, cluster_var / binom_var) if binom_var > 0 else 1.0
    n_eff = F * Q / deff
    k_eff = share * n_eff
    # Clopper–Pearson on a non-integer count: the beta quantiles at (k_eff, n_eff) (Korn & Graubard 1998)
    lo = 0.0 if k_eff <= 0 else float(stats.beta.ppf(0.025, k_eff, n_eff - k_eff + 1))
    hi = 1.0 if k_eff >= n_eff else float(stats.beta.ppf(0.975, k_eff + 1, n_eff - k_eff))
    boot = per_fleet[rng.integers(F, size=(BOOTSTRAP, F))].mean(axis=1)
    return {"k": int(inside.sum()), "n": int(inside.size), "coverage": share, "deff": deff, "n_eff": n_eff,
            "cp95_effective": (lo, hi), "cp95_naive": cp(inside.sum(), inside.size),
            "bootstrap95": tuple(float(x) for x in np.quantile(boot, [0.025, 0.975]))}


def summarise(recs: list[dict], rng: np.random.Generator) -> dict:
    """A row's coverage (pooled and per quantity, per prior), widths, and its fleets' learnt priors."""
    from mtmcal_bayes.parameters import IDENTIFIABLE

    out = {"fleets": len(recs)}
    for p in PRIORS:
        inside = np.array([r[p]["inside"] for r in recs], bool)  # (F, 8)
        out[p] = {"pooled": pooled_coverage(inside, rng),
                  "per_quantity": {q: {"k": int(inside[:, i].sum()), "n": len(recs),
                                       "coverage": float(inside[:, i].mean()), "cp95": cp(inside[:, i].sum(), len(recs))}
                                   for i, q in enumerate(IDENTIFIABLE)},
                  "sigma_median_um": float(np.median([r[p]["sigma_median_um"] for r in recs]))}
    ratio = np.array([np.array(r["learnt"]["width"]) / np.array(r["assumed"]["width"]) for r in recs])
    out["width_ratio_median"] = float(np.median(ratio))
    out["width_ratio_quartiles"] = [float(x) for x in np.quantile(ratio, [0.25, 0.75])]
    med = np.array([r["pooled"]["median_um"] for r in recs])
    out["learnt_median_um_geomean"] = float(np.exp(np.mean(np.log(med))))
    out["learnt_median_um_range"] = [float(med.min()), float(med.max())]
    out["learnt_log_sd_mean"] = float(np.mean([r["pooled"]["log_sd"] for r in recs]))
    out["drift_scale_ln_mean"] = float(np.mean([r["pooled"]["drift_scale"]["mean"] for r in recs]))
    return out


def in_band(e: dict) -> bool:
    """The acceptance: 88–92 %, or a 95 % interval of the share that contains 90 %."""
    lo, hi = e["cp95_effective"]
    return BAND[0] <= e["coverage"] <= BAND[1] or lo <= LEVEL <= hi


def print_tables(doc: dict) -> None:
    from mtmcal_bayes.parameters import IDENTIFIABLE

    rows = doc["rows"]
    print(f"# σ_model learnt by a fleet — {doc['fleets']} fleets per row, {doc['machines']} machines × "
          f"{doc['campaigns']} campaigns (no drift), one new machine per fleet; wall time {doc['wall_s']:.0f} s "
          f"on {doc['workers']} workers\n")
    print("| row | fleet σ, µm | new σ, µm | learnt median, µm (geo-mean; range) | log sd | prior | coverage of 90 % "
          "| 95 % interval (CP, effective n) | bootstrap over fleets | deff | width learnt / assumed | in band |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, fleet_um, new_um, accept in ROWS:
        s = rows[name]
        for p in PRIORS:
            e = s[p]["pooled"]
            learnt, log_sd = ((f"{s['learnt_median_um_geomean']:.2f} ({s['learnt_median_um_range'][0]:.2f}–"
                               f"{s['learnt_median_um_range'][1]:.2f})", f"{s['learnt_log_sd_mean']:.2f}")
                              if p == "learnt" else ("—", "—"))
            print(f"| {name} | {'/'.join(f'{x:g}' for x in fleet_um)} | {new_um:g} | {learnt} | "
                  f"{log_sd} | {p} | {e['coverage']:.3f} | "
                  f"{e['cp95_effective'][0]:.3f}–{e['cp95_effective'][1]:.3f} | "
                  f"{e['bootstrap95'][0]:.3f}–{e['bootstrap95'][1]:.3f} | {e['deff']:.2f} | "
                  f"{s['width_ratio_median']:.2f} | {('yes' if in_band(e) else '**no**') if accept and p == 'learnt' else ''} |")
    print("\n## Per quantity, learnt prior: coverage of 90 % [Clopper–Pearson 95 %], one indicator per fleet\n")
    print("| row | " + " | ".join(IDENTIFIABLE) + " |")
    print("|---|" + "---|" * len(IDENTIFIABLE))
    for name, *_ in ROWS:
        cells = [f"{c['coverage']:.2f} [{c['cp95'][0]:.2f}, {c['cp95'][1]:.2f}]"
                 for c in rows[name]["learnt"]["per_quantity"].values()]
        print(f"| {name} | " + " | ".join(cells) + " |")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fleets", type=int, default=200, help="fleets (each with one new machine) per row")
    ap.add_argument("--machines", type=int, default=4, help="machines per fleet (the shared rows)")
    ap.add_argument("--campaigns", type=int, default=4, help="campaigns per history, 91 days apart")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--quick", action="store_true", help="smoke run: 6 fleets per row")
    ap.add_argument("--seed", type=int, default=20250106)
    ap.add_argument("-o", "--output", default="bench_fleet_sigma.json")
    args = ap.parse_args()
    F = 6 if args.quick else args.fleets
    tasks = [(r, f, args.seed, args.machines, args.campaigns) for r in range(len(ROWS)) for f in range(F)]
    t0 = time.perf_counter()
    recs: list[dict] = []
    with ProcessPoolExecutor(max_workers=args.workers) as ex:
        for rec in ex.map(one_fleet, tasks, chunksize=4):
            recs.append(rec)
            if len(recs) % 100 == 0:
                print(f"[{time.perf_counter() - t0:6.0f} s] {len(recs)}/{len(tasks)} fleets", file=sys.stderr, flush=True)
    wall = time.perf_counter() - t0
    rng = np.random.default_rng(np.random.SeedSequence(args.seed, spawn_key=(len(ROWS),)))
    doc = {"fleets": F, "machines": args.machines, "campaigns": args.campaigns, "seed": args.seed,
           "workers": args.workers, "wall_s": wall, "level": LEVEL, "draws_per_posterior": N_DRAWS,
           "load_average_end": os.getloadavg()[0],
           "rows": {name: {"fleet_sigma_um": fleet_um, "new_sigma_um": new_um, "acceptance": accept,
                           **summarise([x for x in recs if x["row"] == r], rng)}
                    for r, (name, fleet_um, new_um, accept) in enumerate(ROWS)},
           "records": recs}
    print_tables(doc)
    with open(args.output, "w") as fh:
        json.dump(doc, fh, indent=1)
    print(f"\nwrote {os.path.abspath(args.output)}; wall time {wall:.0f} s, load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
