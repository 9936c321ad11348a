"""σ_model learnt by a fleet: how much it narrows a new machine's first campaign, and whether it stays calibrated.

    python bench/fleet_sigma.py [--n 100] [--fleets 20] [--quick] [-o bench_fleet_sigma.json]

Simulated fleets of one machine type (the thesis campaign as the base, ``model="linear"``, no drift): each
machine a history of 4 quarterly campaigns (``synthetic_history``, its deviations drawn from the priors, set-up
offsets fresh each campaign, a model discrepancy σ_model of its own), fitted with ``fit_history(trend="off")``;
each history's likelihood of ln σ (``history_log_likelihood``) pooled by ``pool`` into a new machine's predictive
log-normal, made a ``SigmaModelPrior`` by ``learnt_prior``.

Three kinds of fleet, ``--fleets`` independent fleets of each (every fleet is simulated and pooled afresh):

* ``1.0``: 4 machines, σ_model = 1.0 µm each;  ``3.0``: 4 machines, 3.0 µm each;
* ``mixed``: 3 machines, σ_model 0.5, 1.5 and 4 µm.

Five scenarios, ``--n`` new machines each; new machine j uses fleet ``j mod --fleets`` of its kind.  A new machine
is one campaign (the same simulator), its whole truth (deviations, set-up and mount offsets) drawn from the
campaign's priors, its σ_model set by the scenario.  The new machines of index j are the *same* in every scenario
(common random numbers: the same truth and noise draws, only σ_model differs), so the scenarios compare cleanly;
the assumed-prior results of two scenarios with the same new σ are identical by construction.

| scenario | fleet | new machine σ_model |
|---|---|---|
| shared 1.0 | 1.0 | 1.0 µm |
| shared 3.0 | 3.0 | 3.0 µm |
| new 3× fleet | 1.0 | 3.0 µm |
| new 1/3× fleet | 3.0 | 1.0 µm |
| fleet differs | mixed | 1.5 µm |

Each new campaign's posterior is drawn with the exact sampler (independent draws of the linear model's exact
posterior, σ_model marginalised on a grid: ``mtmcal_bayes.validation.samplers.ExactDraws`` on a ``LogPosterior``,
the engine of ``sample(sampler="exact")`` without its reporting) under the assumed prior (half-normal 2 µm) and
under the learnt one.  The first new machine of every scenario is also run through ``mb.sample(...,
sampler="exact", sigma_model_prior=...)`` and its posterior sds compared with the engine's (``check`` in the JSON).

Per quantity of ``IDENTIFIABLE`` (display units) and prior: posterior sd, the width of the central 95 % interval,
whether the truth lies in the central 50/90/95 % intervals, and the truth's rank among the draws (as a fraction).
Reported: the median ratio learnt/assumed of the 95 % widths and of the sds (narrowing), and the 90 % coverage with
Clopper–Pearson 95 % intervals, pooled over the eight quantities (8·n indicators; they are not independent — see
``cluster_ci``, a bootstrap over fleets) and per quantity.

Everything is seeded from one ``numpy.random.SeedSequence`` (``--seed``).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import sys
import time
import warnings

import numpy as np
from scipy import stats

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.fleets.result import learnt_prior
from mtmcal_bayes.fleets.sigma_model import history_log_likelihood, pool
from mtmcal_bayes.histories import fit_history
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.parameters import IDENTIFIABLE
from mtmcal_bayes.simulation.history import synthetic_history
from mtmcal_bayes.simulation.simulate import synthetic_campaign, truth_from_vector, truth_vector
from mtmcal_bayes.validation.samplers import ExactDraws
from mtmcal_bayes.validation.sbc import quantity_values

FLEETS = {"1.0": (1.0, 1.0, 1.0, 1.0), "3.0": (3.0, 3.0, 3.0, 3.0), "mixed": (0.5, 1.5, 4.0)}
SCENARIOS = (  # name, fleet kind, new machine's σ_model (µm), what it tests
    ("shared 1.0", "1.0", 1.0, "a: shared"),
    ("shared 3.0", "3.0", 3.0, "a: shared"),
    ("new 3× fleet", "1.0", 3.0, "b: new σ 3× the fleet's"),
    ("new 1/3× fleet", "3.0", 1.0, "b: new σ 1/3 of the fleet's"),
    ("fleet differs", "mixed", 1.5, "c: fleet 0.5/1.5/4 µm, new 1.5 µm"),
)
N_CAMPAIGNS = 4
DATES = [datetime.datetime(2025, 1, 6) + datetime.timedelta(days=91 * i) for i in range(N_CAMPAIGNS)]
LEVELS = (0.5, 0.9, 0.95)
N_DRAWS = 4000
PRIORS = ("assumed", "learnt")


def _int(ss: np.random.SeedSequence) -> int:
    return int(ss.generate_state(1)[0])


def draw_truth(space_post: LogPosterior, rng: np.random.Generator) -> tuple[Truth, np.ndarray]:
    """A whole truth (deviations, set-up and mount offsets) from the campaign's priors; σ_model is not drawn."""
    theta = space_post.priors.rvs(1, rng)[0][: space_post.p]
    return truth_from_vector(space_post.space, theta), theta


def simulate_fleet(base, base_post, sigmas_um, ss: np.random.SeedSequence) -> dict:
    """One fleet: a history per machine, each pooled; its predictive and the prior made of it."""
    rows = []
    for k, (s, child) in enumerate(zip(sigmas_um, ss.spawn(len(sigmas_um)))):
        rng = np.random.default_rng(child)
        truth, _ = draw_truth(base_post, rng)
        truth = Truth(dict(truth.deviations))  # set-up offsets: synthetic_history draws them afresh per campaign
        camps = synthetic_history(base, truth, DATES, serial=f"F-{k + 1}", seed=int(rng.integers(2**31)),
                                  sigma_model=units.to_internal(s, "um"))
        r = fit_history(camps, seed=int(rng.integers(2**31)), trend="off")
        rows.append(history_log_likelihood(r.fit.model, r.fit.q2))
    pooled = {"type": "SIM", "machines": len(sigmas_um), **pool(rows)}
    return {"pooled": pooled, "prior": learnt_prior(pooled, "bench/fleet_sigma.py simulated fleet")}


def posterior_draws(campaign, prior, rng) -> tuple[LogPosterior, np.ndarray]:
    post = LogPosterior(campaign, "linear", sigma_prior=prior)
    d = ExactDraws(n_all=N_DRAWS)(post, 0, rng)  # a fresh sampler: its cache is keyed by id(post.forward)
    return post, d.all


def summarise(post: LogPosterior, draws: np.ndarray, truth_theta: np.ndarray) -> dict:
    q = quantity_values(post, draws)[:, : len(IDENTIFIABLE)]
    t = quantity_values(post, np.append(truth_theta, 0.0)[None])[0, : len(IDENTIFIABLE)]
    out = {"sd": q.std(axis=0, ddof=1), "rank": (q < t).mean(axis=0)}
    for lev in LEVELS:
        lo, hi = np.quantile(q, [(1 - lev) / 2, (1 + lev) / 2], axis=0)
        out[f"in{int(lev * 100)}"] = (lo <= t) & (t <= hi)
        if lev == 0.95:
            out["w95"] = hi - lo
    out["sigma_median_um"] = float(units.from_internal(np.median(draws[:, post.p]), "um"))
    return out


def one_machine(base, base_post, sigma_um, fleet, ss: np.random.SeedSequence) -> dict:
    rng = np.random.default_rng(ss)
    truth, _ = draw_truth(base_post, rng)
    c = synthetic_campaign(base, truth, "linear", noise=True, seed=int(rng.integers(2**31)),
                           sigma_model=units.to_internal(sigma_um, "um"))
    sample_seed = int(rng.integers(2**31))
    out = {}
    for name, prior in (("assumed", None), ("learnt", fleet["prior"])):
        post, draws = posterior_draws(c, prior, np.random.default_rng([sample_seed, PRIORS.index(name)]))
        out[name] = summarise(post, draws, truth_vector(post.space, truth))
    out["campaign"] = c
    return out


def check_against_sample(rec: dict, prior) -> dict:
    """The same campaign through ``mb.sample(sampler="exact")``: the largest relative difference of the sds."""
    out = {}
    for name, p in (("assumed", None), ("learnt", prior)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = mb.sample(rec["campaign"], sampler="exact", seed=7, sigma_model_prior=p)
        sd = r.summary.loc[list(IDENTIFIABLE), "sd"].to_numpy(float)
        out[name] = float(np.max(np.abs(sd / rec[name]["sd"] - 1)))
    return out


def cp(k: int, n: int) -> tuple[float, float]:
    ci = stats.binomtest(int(k), int(n)).proportion_ci(confidence_level=0.95, method="exact")
    return float(ci.low), float(ci.high)


def cluster_ci(hits: np.ndarray, fleet_of: np.ndarray, rng: np.random.Generator, B: int = 2000) -> tuple[float, float]:
    """95 % percentile bootstrap of the pooled coverage, resampling fleets (new machines of one fleet share its
    prior, and the eight quantities of one machine share its data: neither is independent)."""
    ids = np.unique(fleet_of)
    per = np.array([hits[fleet_of == f].sum() for f in ids], float)
    cnt = np.array([hits[fleet_of == f].size for f in ids], float)
    pick = rng.integers(len(ids), size=(B, len(ids)))
    cov = per[pick].sum(axis=1) / cnt[pick].sum(axis=1)
    return float(np.quantile(cov, 0.025)), float(np.quantile(cov, 0.975))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100, help="new machines per scenario")
    ap.add_argument("--fleets", type=int, default=None, help="independent fleets of each kind (default n/5)")
    ap.add_argument("--quick", action="store_true", help="smoke run: n = 10, 2 fleets of each kind")
    ap.add_argument("--seed", type=int, default=20250106)
    ap.add_argument("-o", "--output", default="bench_fleet_sigma.json")
    args = ap.parse_args()
    n = 10 if args.quick else args.n
    n_fleets = 2 if args.quick else (args.fleets or max(1, n // 5))
    n_fleets = min(n_fleets, n)
    t_start = time.perf_counter()
    root = np.random.SeedSequence(args.seed)
    ss_fleets, ss_new, ss_boot = root.spawn(3)
    base = mb.load_campaign()
    base_post = LogPosterior(base, "linear")

    # --- fleets ---
    fleets: dict[str, list[dict]] = {}
    for kind, ss_kind in zip(FLEETS, ss_fleets.spawn(len(FLEETS))):
        fleets[kind] = []
        for f, ss in enumerate(ss_kind.spawn(n_fleets)):
            fleets[kind].append(simulate_fleet(base, base_post, FLEETS[kind], ss))
            p = fleets[kind][-1]["pooled"]
            print(f"[{time.perf_counter() - t_start:6.0f} s] fleet {kind} #{f}: median {p['median_um']:.2f} µm, "
                  f"log sd {p['log_sd']:.2f}, τ {p['tau']['mean']:.2f}", file=sys.stderr, flush=True)

    # --- new machines ---
    machine_ss = ss_new.spawn(n)
    results: dict[str, list[dict]] = {}
    checks = {}
    for name, kind, sigma_um, _ in SCENARIOS:
        recs = []
        for j in range(n):
            fleet = fleets[kind][j % n_fleets]
            rec = one_machine(base, base_post, sigma_um, fleet, machine_ss[j])
            if j == 0:
                checks[name] = check_against_sample(rec, fleet["prior"])
            rec.pop("campaign")
            rec["fleet"] = j % n_fleets
            recs.append(rec)
        results[name] = recs
        print(f"[{time.perf_counter() - t_start:6.0f} s] scenario {name}: done", file=sys.stderr, flush=True)
    wall = time.perf_counter() - t_start

    # --- tables ---
    brng = np.random.default_rng(ss_boot)
    Q = list(IDENTIFIABLE)
    doc = {"n": n, "fleets_per_kind": n_fleets, "seed": args.seed, "campaigns_per_history": N_CAMPAIGNS,
           "fleet_kinds_um": FLEETS, "draws_per_posterior": N_DRAWS, "wall_s": wall,
           "load_average_end": os.getloadavg()[0], "check_vs_mb_sample_max_rel_sd_diff": checks,
           "fleets": {k: [f["pooled"] for f in v] for k, v in fleets.items()}, "scenarios": {}}

    print(f"# σ_model learnt by a fleet — {n} new machines per scenario, {n_fleets} fleets of each kind, "
          f"{N_CAMPAIGNS} campaigns per history; wall time {wall:.0f} s\n")
    print("## Fleets' learnt priors (mean over the fleets of each kind; range)\n")
    print("| fleet (σ_model of its machines, µm) | predictive median, µm | log sd | τ (posterior mean) |")
    print("|---|---|---|---|")
    for kind, v in fleets.items():
        med = np.array([f["pooled"]["median_um"] for f in v])
        lsd = np.array([f["pooled"]["log_sd"] for f in v])
        tau = np.array([f["pooled"]["tau"]["mean"] for f in v])
        print(f"| {kind} ({', '.join(f'{s:g}' for s in FLEETS[kind])}) | {np.exp(np.mean(np.log(med))):.2f} "
              f"({med.min():.2f}–{med.max():.2f}) | {lsd.mean():.2f} ({lsd.min():.2f}–{lsd.max():.2f}) | "
              f"{tau.mean():.2f} ({tau.min():.2f}–{tau.max():.2f}) |")
    print("\nassumed prior: half-normal, scale 2 µm (median 1.35 µm)\n")

    print("## Narrowing: learnt / assumed, median over new machines\n")
    print("| scenario | 95 % width ratio, median over 8 quantities × machines | sd ratio | "
          + " | ".join(Q) + " |")
    print("|---|---|---|" + "---|" * len(Q))
    for name, kind, sigma_um, label in SCENARIOS:
        recs = results[name]
        w = np.array([r["learnt"]["w95"] / r["assumed"]["w95"] for r in recs])  # (n, 8)
        s = np.array([r["learnt"]["sd"] / r["assumed"]["sd"] for r in recs])
        per_q = np.median(w, axis=0)
        sig = {p: float(np.median([r[p]["sigma_median_um"] for r in recs])) for p in PRIORS}
        doc["scenarios"][name] = {"fleet": kind, "new_sigma_um": sigma_um, "label": label,
                                  "width95_ratio_median": float(np.median(w)), "sd_ratio_median": float(np.median(s)),
                                  "width95_ratio_quartiles": [float(x) for x in np.quantile(w, [0.25, 0.75])],
                                  "width95_ratio_per_quantity": dict(zip(Q, map(float, per_q))),
                                  "posterior_sigma_median_um": sig}
        print(f"| {name} | {np.median(w):.2f} (IQR {np.quantile(w, 0.25):.2f}–{np.quantile(w, 0.75):.2f}) | "
              f"{np.median(s):.2f} | " + " | ".join(f"{x:.2f}" for x in per_q) + " |")

    print("\n## Coverage of the central 90 % interval (truth inside), pooled over the 8 quantities\n")
    print("CP: Clopper–Pearson 95 % on 8·n indicators (treats them as independent); fleet bootstrap: "
          "95 % interval resampling fleets (honest about the sharing)\n")
    print("| scenario | prior | coverage 90 % | CP 95 % | fleet bootstrap | coverage 50 % | coverage 95 % |")
    print("|---|---|---|---|---|---|---|")
    for name, kind, sigma_um, label in SCENARIOS:
        recs = results[name]
        fleet_of = np.repeat([r["fleet"] for r in recs], len(Q))
        for p in PRIORS:
            entry = {}
            for lev in LEVELS:
                key = f"in{int(lev * 100)}"
                hits = np.concatenate([r[p][key] for r in recs])
                k, m = int(hits.sum()), hits.size
                per = np.array([r[p][key] for r in recs])  # (n, 8)
                entry[key] = {"k": k, "n": m, "coverage": k / m, "cp95": cp(k, m),
                              "fleet_bootstrap95": cluster_ci(hits, fleet_of, brng),
                              "per_quantity": {q: {"k": int(per[:, i].sum()), "n": len(recs),
                                                   "coverage": float(per[:, i].mean()),
                                                   "cp95": cp(per[:, i].sum(), len(recs))} for i, q in enumerate(Q)}}
            per90 = np.array([r[p]["in90"].mean() for r in recs])
            fl = np.array([r["fleet"] for r in recs])
            entry["in90_per_fleet"] = [{"fleet": int(f), "median_um": fleets[kind][f]["pooled"]["median_um"],
                                        "log_sd": fleets[kind][f]["pooled"]["log_sd"],
                                        "coverage": float(per90[fl == f].mean()), "machines": int((fl == f).sum())}
                                       for f in np.unique(fl)]
            ranks = np.array([r[p]["rank"] for r in recs])
            entry["rank_uniformity_ks_p_per_quantity"] = {
                q: float(stats.kstest(ranks[:, i], "uniform").pvalue) for i, q in enumerate(Q)}
            doc["scenarios"][name][p] = entry
            e = entry["in90"]
            print(f"| {name} | {p} | {e['coverage']:.3f} | {e['cp95'][0]:.3f}–{e['cp95'][1]:.3f} | "
                  f"{e['fleet_bootstrap95'][0]:.3f}–{e['fleet_bootstrap95'][1]:.3f} | "
                  f"{entry['in50']['coverage']:.3f} | {entry['in95']['coverage']:.3f} |")

    print("\n## Coverage of the central 90 % interval per quantity (learnt / assumed; n per cell)\n")
    print("| scenario | " + " | ".join(Q) + " |")
    print("|---|" + "---|" * len(Q))
    for name, *_ in SCENARIOS:
        cells = []
        for q in Q:
            a = doc["scenarios"][name]["assumed"]["in90"]["per_quantity"][q]["coverage"]
            l_ = doc["scenarios"][name]["learnt"]["in90"]["per_quantity"][q]["coverage"]
            cells.append(f"{l_:.2f} / {a:.2f}")
        print(f"| {name} | " + " | ".join(cells) + " |")
    print(f"\nper-quantity CP half-width at n = {n}, 90 %: ±{(cp(round(0.9 * n), n)[1] - cp(round(0.9 * n), n)[0]) / 2:.2f}")
    print(f"\ncheck (engine vs mb.sample, max relative sd difference, first machine of each scenario): "
          + ", ".join(f"{k}: {v['assumed']:.3f}/{v['learnt']:.3f}" for k, v in checks.items()))

    with open(args.output, "w") as fh:
        json.dump(doc, fh, indent=1, default=lambda x: x.tolist() if isinstance(x, np.ndarray) else str(x))
    print(f"\nwrote {os.path.abspath(args.output)}; wall time {wall:.0f} s, load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
