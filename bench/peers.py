"""The thesis posterior in NumPyro and PyMC (NUTS, dense mass) against the package's sampler and the exact limit.

    pip install ".[bench]"            # NumPyro and PyMC, for this comparison only
    python bench/peers.py [--repeats 3] [--skip numpyro,pymc] [--package-python .venv/bin/python]

The posterior is the ``linear`` model of the built-in thesis campaign with
sigma_model free (25 sampled dimensions): exported from the package as its
design matrix, data, noise variances and priors, and written again in each
peer (non-centred: z ~ N(0, 1), θ = prior sd · z; sigma_model = prior scale · s,
s ~ HalfNormal(1); float64).  Every method runs as a fresh process, so its
time is the whole process — imports, JIT compilation, sampling, diagnostics —
and to the same targets: bulk and tail ESS ≥ 1000 for each of the eight
quantities of Table 4.5, ≥ 400 for sigma_model, R-hat ≤ 1.01 (ArviZ, the same
code for all).  A peer gets the fewest draws per chain (4 chains, 500 warm-up
steps) that meet the targets at its seed.  The equivalence of the peers'
models is checked against the exact σ-marginal posterior (means within 0.05 sd,
sds within 5 %), and every method's accuracy is stated against it.

Prints one table: wall time (median of ``--repeats``), its ratio to
``mtmcal-bayes sample``, diagnostics and accuracy.

``--package-python`` runs the package from another environment: the bench
extra brings numba (through PyMC), and ArviZ compiles with numba on import when
it is installed, which adds most of a second to every process that imports it.
A package installed as the README says has no numba; time it from such an
environment for the comparison a user sees.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
TARGET_ESS, TARGET_ESS_SIGMA, MAX_RHAT = 1000.0, 400.0, 1.01
WARMUP, CHAINS = 500, 4
DRAW_LADDER = (250, 500, 750, 1000, 1500, 2000)

#: what the peer scripts print: for the eight, dx_CZ−dx_BT from θ by the package's weights; display units
_SUMMARY = r'''
import json, sys, time
import numpy as np
import arviz as az

def summarise(theta, s, d, t_sampling):
    """theta (chains, draws, p) internal units, s (chains, draws) sigma_model / scale."""
    q = np.einsum("cdp,tp->cdt", theta, d["T"]) / d["display"]
    out = {}
    names = list(d["names"])
    for i, n in enumerate(names):
        x = q[..., i]
        out[n] = dict(mean=float(x.mean()), sd=float(x.std()), ess_bulk=float(az.ess(x, method="bulk")),
                      ess_tail=float(az.ess(x, method="tail")), r_hat=float(az.rhat(x)))
    x = s * float(d["sigma_scale_um"])
    out["sigma_model"] = dict(mean=float(x.mean()), sd=float(x.std()), ess_bulk=float(az.ess(x, method="bulk")),
                              ess_tail=float(az.ess(x, method="tail")), r_hat=float(az.rhat(x)))
    print(json.dumps({"summary": out, "sampling_s": t_sampling}))
'''

NUMPYRO = _SUMMARY + r'''
import jax
jax.config.update("jax_enable_x64", True)
import jax.numpy as jnp
import numpyro, numpyro.distributions as dist
from numpyro.infer import MCMC, NUTS
d = dict(np.load(sys.argv[1], allow_pickle=True))
draws, warmup, chains, seed = (int(v) for v in sys.argv[2:6])
A, y, b, sd0 = (jnp.asarray(d[k]) for k in ("A_um", "y_um", "base_var_um2", "prior_sd"))
scale = float(d["sigma_scale_um"])

def model():
    z = numpyro.sample("z", dist.Normal(0.0, 1.0).expand([A.shape[1]]))
    s = numpyro.sample("s", dist.HalfNormal(1.0))
    numpyro.sample("y", dist.Normal(A @ (z * sd0), jnp.sqrt(b + (s * scale) ** 2)), obs=y)

t0 = time.perf_counter()
mcmc = MCMC(NUTS(model, dense_mass=True), num_warmup=warmup, num_samples=draws, num_chains=chains,
            chain_method="vectorized", progress_bar=False)
mcmc.run(jax.random.PRNGKey(seed))
s = mcmc.get_samples(group_by_chain=True)
t = time.perf_counter() - t0
summarise(np.asarray(s["z"]) * np.asarray(sd0), np.asarray(s["s"]), d, t)
'''

PYMC = _SUMMARY + r'''
import pymc as pm
import pytensor.tensor as pt
d = dict(np.load(sys.argv[1], allow_pickle=True))
draws, warmup, chains, seed = (int(v) for v in sys.argv[2:6])
A, y, b, sd0 = (d[k] for k in ("A_um", "y_um", "base_var_um2", "prior_sd"))
scale = float(d["sigma_scale_um"])
t0 = time.perf_counter()
with pm.Model():
    z = pm.Normal("z", 0.0, 1.0, shape=A.shape[1])
    s = pm.HalfNormal("s", 1.0)
    pm.Normal("y", pt.dot(A, z * sd0), pt.sqrt(b + (s * scale) ** 2), observed=y)
    idata = pm.sample(draws=draws, tune=warmup, chains=chains, cores=2, init="jitter+adapt_full", random_seed=seed,
                      progressbar=False, compute_convergence_checks=False)
t = time.perf_counter() - t0
post = idata.posterior
summarise(post["z"].values * sd0, post["s"].values, d, t)
'''


def export(path: Path) -> dict:
    """The thesis linear posterior as arrays (µm units for the data), and its exact moments."""
    import mtmcal_bayes as mb
    from mtmcal_bayes.inference import LogPosterior, PosteriorApproximation
    from mtmcal_bayes.parameters import IDENTIFIABLE, quantity_unit, weights

    post = LogPosterior(mb.load_campaign(), "linear")
    priors = post.priors.priors
    T = np.zeros((len(IDENTIFIABLE), post.p))
    for i, n in enumerate(IDENTIFIABLE):
        for k, w in weights(n, post.names).items():
            T[i, post.names.index(k)] = w
    display = np.array([mb.units.to_internal(1.0, quantity_unit(n)) for n in IDENTIFIABLE])
    np.savez(path, A_um=post.forward.design * 1e3, y_um=post.likelihood.y * 1e3,
             base_var_um2=post.likelihood.base_var * 1e6, prior_sd=np.array([p.sd for p in priors[: post.p]]),
             sigma_scale_um=priors[-1].scale * 1e3, T=T, display=display, names=np.array(IDENTIFIABLE))
    exact = PosteriorApproximation(post).moments(list(IDENTIFIABLE) + ["sigma_model"])
    return {n: {"mean": m, "sd": s} for n, (m, s) in exact.items()}


def timed(argv: list[str]) -> tuple[float, dict]:
    """Wall time of a fresh process and the JSON it prints last."""
    t0 = time.perf_counter()
    out = subprocess.run(argv, check=True, capture_output=True, text=True, env={**os.environ, "PYTHONWARNINGS": "ignore"})
    wall = time.perf_counter() - t0
    return wall, json.loads(out.stdout.strip().splitlines()[-1] if argv[1] == "-c" else out.stdout)


def meets_targets(summary: dict) -> bool:
    for n, r in summary.items():
        target = TARGET_ESS_SIGMA if n == "sigma_model" else TARGET_ESS
        if min(r["ess_bulk"], r["ess_tail"]) < target or r["r_hat"] > MAX_RHAT:
            return False
    return True


def accuracy(summary: dict, exact: dict) -> tuple[float, float]:
    eight = [n for n in summary if n != "sigma_model"]
    dm = max(abs(summary[n]["mean"] - exact[n]["mean"]) / exact[n]["sd"] for n in eight)
    ds = max(abs(summary[n]["sd"] / exact[n]["sd"] - 1.0) for n in eight)
    return dm, 100.0 * ds


def package_run(python: str, extra: list[str], seed: int = 1) -> tuple[float, dict]:
    """``mtmcal-bayes sample`` of the environment of ``python``, as a fresh process."""
    from mtmcal_bayes.parameters import IDENTIFIABLE

    sibling = Path(python).with_name("mtmcal-bayes")
    exe = str(sibling) if sibling.exists() else shutil.which("mtmcal-bayes")
    wall, doc = timed([exe, "sample", "--seed", str(seed), "--quiet", "--json", *extra])
    s = {n: {k: doc["summary"][n][k] for k in ("mean", "sd", "ess_bulk", "ess_tail", "r_hat")}
         for n in list(IDENTIFIABLE) + ["sigma_model"]}
    return wall, {"summary": s, "sampling_s": doc["diagnostics"]["wall_time_s"]}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--repeats", type=int, default=3, help="timed runs per method (median reported)")
    ap.add_argument("--skip", default="", help="comma-separated peers to leave out (numpyro, pymc)")
    ap.add_argument("--accuracy-seeds", type=int, default=5,
                    help="seeds over which each method's accuracy is averaged (default 5)")
    ap.add_argument("--package-python", default=sys.executable,
                    help="interpreter whose environment runs mtmcal-bayes (default: this one)")
    args = ap.parse_args()
    skip = set(filter(None, args.skip.split(",")))
    tmp = Path(tempfile.mkdtemp(prefix="peers-"))
    npz = tmp / "posterior.npz"
    exact = export(npz)

    methods = {"mtmcal-bayes sample": lambda seed=1: package_run(args.package_python, [], seed),
               "mtmcal-bayes sample --sampler exact":
                   lambda seed=1: package_run(args.package_python, ["--sampler", "exact"], seed)}
    for name, script in (("numpyro", NUMPYRO), ("pymc", PYMC)):
        if name in skip:
            continue
        chosen = None
        for draws in DRAW_LADDER:  # the fewest draws that meet the targets
            _, doc = timed([sys.executable, "-c", script, str(npz), str(draws), str(WARMUP), str(CHAINS), "1"])
            dm, ds = accuracy(doc["summary"], exact)
            print(f"  {name}: {draws} draws/chain: targets {'met' if meets_targets(doc['summary']) else 'missed'}, "
                  f"means within {dm:.3f} sd, sds within {ds:.1f} % of exact", file=sys.stderr)
            if meets_targets(doc["summary"]):
                chosen = draws
                break
        if chosen is None:
            print(f"  {name}: no draw count up to {DRAW_LADDER[-1]} met the targets; left out", file=sys.stderr)
            continue
        label = f"{'NumPyro' if name == 'numpyro' else 'PyMC'} NUTS dense, {CHAINS}×({WARMUP}+{chosen})"
        methods[label] = (lambda seed=1, s=script, n=chosen: timed([sys.executable, "-c", s, str(npz), str(n),
                                                                     str(WARMUP), str(CHAINS), str(seed)]))

    rows = []
    for label, run in methods.items():
        walls, doc = [], None
        for _ in range(args.repeats):
            wall, doc = run()
            walls.append(wall)
        s = doc["summary"]
        errors = [accuracy(s, exact)] + [accuracy(run(seed)[1]["summary"], exact)
                                         for seed in range(2, args.accuracy_seeds + 1)]
        dm, ds = np.mean(errors, axis=0)
        eight = [n for n in s if n != "sigma_model"]
        rows.append((label, float(np.median(walls)), doc["sampling_s"], min(s[n]["ess_bulk"] for n in eight),
                     min(s[n]["ess_tail"] for n in eight), s["sigma_model"]["ess_bulk"], max(r["r_hat"] for r in s.values()),
                     dm, ds, meets_targets(s)))
    ours = rows[0][1]
    peers = [r[1] for r in rows if "NUTS" in r[0]]
    print(f"Thesis campaign, linear model, sigma_model free (25 dimensions); {args.repeats} timed runs each, median; "
          f"{os.cpu_count()} cores; package from {args.package_python}, peers from {sys.executable}")
    print(f"Diagnostics of the seed-1 run; Δmean (in exact sd) and Δsd (%): the largest over the eight quantities, "
          f"averaged over {args.accuracy_seeds} seeds")
    print(f"{'method':42s} {'wall s':>7s} {'÷ ours':>7s} {'sampling s':>10s} {'bulk ESS':>9s} {'tail ESS':>9s} "
          f"{'σ ESS':>7s} {'R-hat':>6s} {'Δmean sd':>9s} {'Δsd %':>6s} targets")
    for label, wall, samp, eb, et, es, rh, dm, ds, ok in rows:
        print(f"{label:42s} {wall:7.2f} {wall / ours:7.2f} {samp:10.2f} {eb:9.0f} {et:9.0f} {es:7.0f} {rh:6.3f} "
              f"{dm:9.3f} {ds:6.1f} {'met' if ok else 'MISSED'}")
    if peers:
        print(f"mtmcal-bayes sample is {min(peers) / ours:.1f}× faster (whole process) than the faster NUTS peer.")
    shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
