"""Does a design with every instrument keep its promise through the kinematics?  (issue 44 item 2, validation)

For each built-in type a new machine: its demo's description, ball-bar set-ups and mounts, its ``[probe]`` (the
stylus, the repeatability) and the ``[rtest]`` of its demo or of its R-test demo (the nest, the sensors'
repeatability), no run of any instrument; the sphere of the probe and of the R-test stated where the demo's first
run has it (``[rtest] sphere_mm``, else the probe's first run: the catalogues' sphere of a campaign without runs,
docs/design.md "Every instrument").  ``design`` with every instrument to 3″ for every determinable angle and 5 µm for
every determinable length (relaxed by 25 % steps where the catalogue cannot reach them: ``design_described``),
σ_model contraction 0.5; with ``--probe`` the probe-only design of ``bench/design_instruments.py`` (the type's
description with a ``[probe]`` alone, ``--instruments probe``), its sphere's run replaced by a W-ball mount at the
sphere (:func:`new_probe_machine`: a new machine, no reading in the design's posterior).

Then ``N`` machines drawn from the priors — every deviation and every nuisance term of the designed campaign's
posterior (the ball bar's set-ups and placements, each probe run's stylus and sphere, the R-test's nest, placement and
zeros; on the thesis machine not the linear axes' squareness, which its model leaves out) and every discrepancy scale
— measured through the machine's kinematics (a described machine's chain, the thesis plug-in's ``htm-thesis``: the
models the design's check simulates through): the designed runs as campaign runs (the probe's and the R-test's as
the tables to fill in become once measured), simulated by ``synthetic_campaign`` (the ball bar's repeat scatter,
instrument error and σ_model; the probe's and R-test's repeatability), each probe and R-test reading with its own
discrepancy ``N(0, σ_model_probe²)``, ``N(0, σ_model_rtest²)`` shared by its repeats; each machine's exact posterior
(the posterior ``sample --sampler exact`` draws from: every instrument's data, every scale integrated out; its sds in
closed form, :func:`realised_sd`, the draws' compared on the first three machines).  Per target: the mean realised
sd, the share of machines meeting it with its Clopper–Pearson 95 % interval (``scipy.stats.binomtest``), beside the
design's own check (400 machines; through the kinematics or not, :mod:`mtmcal_bayes.planning.design_chain`).  The
promise holds where the interval contains :data:`~mtmcal_bayes.planning.design_problem.PROMISE` or lies above it
(where the check itself finds a target short of it, the check's share).  Then, per target, the machines' sds against
the check's at the same discrepancy scale (:func:`given_scale`): whether the two simulate one population.

Run: ``python bench/design_every_instrument.py [N] [--probe] [--from=K] [--merge] [TYPE ...]`` (default 50 machines,
every built-in type, the thesis machine's last).  With ``DESIGN_BENCH_OUT=DIR`` each type's design is kept (and read
again next time) and its machines' sds as they come: ``--from=K`` infers machines K … N−1 only (the earlier ones
drawn and simulated, not inferred: several processes share one population), ``--merge`` prints the table of every
machine kept.
"""

from __future__ import annotations

import copy
import os
import pickle
import sys
import time
from pathlib import Path

import cloudpickle
import numpy as np

from mtmcal_bayes import api
from mtmcal_bayes.analysis import analysis_of
from mtmcal_bayes.campaign import Mount, Probe, RTest, RTestNest
from mtmcal_bayes.errors import ParameterError
from mtmcal_bayes.inference.log_posterior import parameter_space
from mtmcal_bayes.inference.priors import make_prior
from mtmcal_bayes.planning.design_check import preposterior
from mtmcal_bayes.planning.design_instruments import other_candidates, taught
from mtmcal_bayes.planning.design_make import design_candidates, reporting_planner
from mtmcal_bayes.planning.design_output import designed_campaign
from mtmcal_bayes.planning.design_problem import PROMISE
from mtmcal_bayes.planning.design_timing import SESSION
from mtmcal_bayes.models import default_kinematic_model
from mtmcal_bayes.planning.machine_kit import planner_for
from mtmcal_bayes.planning.scale_priors import scale_prior
from mtmcal_bayes.simulation.simulate import synthetic_campaign, truth_from_vector

sys.path.insert(0, str(Path(__file__).parent))
from design_described import design_to, share_table
from design_instruments import probe_only

ARGS = [a for a in sys.argv[1:] if not a.startswith("--")]
PROBE_ONLY = "--probe" in sys.argv
#: this process's first machine (``--from=K``: machines K … N−1, the earlier ones drawn but not inferred, so that
#: several processes share one population); ``--merge``: no machine, the kept ones' table
FIRST = int(next((a.split("=")[1] for a in sys.argv if a.startswith("--from=")), 0))
MERGE = "--merge" in sys.argv
TYPES = tuple(a for a in ARGS if not a.isdigit()) or ("trunnion", "head-head", "vertical-turn-mill", "nutating-head",
                                                         "integrex-i200")
#: machines whose closed-form sds are compared with the sampler's draws (``sample --sampler exact``)
AGAINST_DRAWS = 3
#: the discrepancy scale of each instrument's readings
SCALES = {"ballbar": "sigma_model", "probe": "sigma_model_probe", "rtest": "sigma_model_rtest"}


def new_machine(kind: str):
    """The type's new machine with every instrument's set-up and no run (module docstring)."""
    c = copy.deepcopy(api.campaign_of(api.demo_campaign(kind)))
    if c.rtest is None:
        try:
            c.rtest = copy.deepcopy(api.campaign_of(api.rtest_demo_campaign(kind)).rtest)
        except ParameterError:  # a type without an R-test demo: its new machine has no R-test
            c.rtest = None
    if c.rtest is not None and c.rtest.sphere is None and c.rtest.runs:
        c.rtest.sphere = np.asarray(c.rtest.runs[0].sphere, float)
    if c.rtest is not None and c.rtest.sphere is None and c.probe is not None and c.probe.runs:
        c.rtest.sphere = np.asarray(c.probe.runs[0].sphere, float)
    if c.rtest is not None:
        c.rtest.runs = []
    c.ballbar.runs, c.probe.runs, c.truth = [], [], None
    return c


def new_probe_machine(kind: str):
    """The type's probe-only machine of ``bench/design_instruments.py`` made new: its probe run (there to place the
    sphere, and whose readings the design's posterior would take) replaced by a W-ball mount at the sphere, where the
    probe catalogue of a campaign without probe runs puts its sphere (no ball-bar set-up: not an instrument here)."""
    c, _ = probe_only(kind)
    sphere = np.asarray(c.probe.runs[0].sphere, float)
    c.probe.runs = []
    c.ballbar.mounts = {"sphere": Mount("sphere", float(sphere[2]), 0.0, position=sphere)}
    return c


def measured(d):
    """The designed campaign with its probe and R-test runs as campaign runs (zero readings: to be simulated)."""
    c = copy.deepcopy(designed_campaign(d))
    probe = [r.measured for r in d.runs if r.instrument == "probe"]
    rtest = [r.measured for r in d.runs if r.instrument == "rtest"]
    if probe:
        runs = [p.probe_run() for p in probe]
        c.probe = Probe(c.probe.instrument, c.probe.repeatability, runs=runs,
                        styli={run.stylus: p.stylus_length for run, p in zip(runs, probe)})
    else:
        c.probe = None
    if rtest:
        rt = c.rtest
        c.rtest = RTest(rt.instrument, rt.repeatability, rt.placement_sd, rt.nest_length_sd, rt.nest_offset_sd,
                        nests={r.setup.nest: RTestNest(r.setup.length, r.setup.calibrated) for r in rtest},
                        runs=[r.run() for r in rtest])
    else:
        c.rtest = None
    return c


def draw_machine(c, rng):
    """A machine from the priors: every deviation and nuisance term of the space ``c``'s posterior has (its machine's
    plug-in's where it has one: the thesis' leaves out the linear axes' squareness, which its model does not
    estimate; the design's check draws that space too), and every scale."""
    space = parameter_space(c, False, data_of(c))
    stated = c.rtest.prior_sds() if c.rtest is not None else None
    theta = [make_prior(p.name, p.base, p.kind, c.priors, stated=stated).frozen().rvs(random_state=rng)
             for p in space.parameters]
    sigmas = {i: float(scale_prior(c, s, None).frozen().rvs(random_state=rng)) for i, s in SCALES.items()}
    return truth_from_vector(space, np.asarray(theta, float)), sigmas


def data_of(c) -> str:
    """The likelihood's data: every instrument the designed campaign has runs of."""
    have = [bool(c.ballbar.runs or c.ballbar.planned), c.probe is not None and bool(c.probe.runs),
            c.rtest is not None and bool(c.rtest.runs)]
    if have[2]:
        return "all"
    return "both" if have[0] and have[1] else "probe" if have[1] else "ballbar"


def simulate(c, truth, sigmas, rng):
    """``c`` measured on the machine ``truth`` through its kinematics — the machine's default kinematic model, the
    one the design's check simulates through (a described machine's chain, the thesis plug-in's ``htm-thesis``) —
    every reading with its scale's discrepancy."""
    syn = synthetic_campaign(c, truth, default_kinematic_model(c.machine), noise=True, seed=int(rng.integers(2**31)),
                             sigma_model=sigmas["ballbar"])
    if syn.probe is not None:
        for run in syn.probe.runs:
            run.replace_centres(run.centres + rng.normal(0.0, sigmas["probe"], run.centres.shape[1:]))
    if syn.rtest is not None:
        for run in syn.rtest.runs:
            run.displacements = run.displacements + rng.normal(0.0, sigmas["rtest"], run.displacements.shape[1:])
    return syn


def realised_sd(syn, targets, data: str) -> list[float]:
    """Each target's sd (display units) in the exact σ-marginal posterior of the simulated campaign ``syn`` — the
    posterior ``sample --sampler exact`` draws from (linear model, every scale integrated out on its grid) — in
    closed form: the draws' sd without their Monte-Carlo error, in a third less time."""
    approx = analysis_of(syn, model="linear", data=data, sigma_model=None, sigma_prior=None).approximation
    assert approx.exact, approx.kind
    m = approx.moments(list(targets))
    return [m[q][1] for q in targets]


def design_for(kind: str):
    """The type's machine, its targets (3″ / 5 µm on every deviation its candidates determine) and its design."""
    if PROBE_ONLY:
        c = new_probe_machine(kind)
        p = planner_for(c, other_candidates(c, ["probe"]), None)
        settings = {"instruments": "probe"}
    else:
        c = new_machine(kind)
        p = planner_for(c, design_candidates(c) + other_candidates(c, ["probe", "rtest"]), None)
        settings = {}
    targets = {q: (3.0 if p.table[q].unit == "arcsec" else 5.0) for q in p.targets}
    d, relaxed = design_to(c, targets, **settings)
    return d, relaxed, p.not_targeted


def _cached(kind: str, make):
    """``make(kind)``, kept in ``OUT/<kind>-design.pkl`` (``DESIGN_BENCH_OUT``) and read from there next time."""
    out = os.environ.get("DESIGN_BENCH_OUT")
    path = Path(out or ".") / f"{kind}{'-probe' if PROBE_ONLY else ''}-design.pkl"
    if out and path.is_file():
        return pickle.loads(path.read_bytes())
    made = make(kind)
    if out:
        Path(out).mkdir(parents=True, exist_ok=True)
        try:  # cloudpickle: the design's clock holds a closure
            path.write_bytes(cloudpickle.dumps(made))
        except (pickle.PicklingError, TypeError, AttributeError) as err:
            print(f"  (design not kept: {err})")
    return made


def _keep(kind: str, d, first: int, sds, scales_drawn) -> None:
    """The realised sds (k, t) and the drawn scales (k, 3) of machines ``first``, ``first + 1``, … to
    ``OUT/<kind>-from<first>.npz`` (``OUT``: the environment's ``DESIGN_BENCH_OUT``, else nothing kept)."""
    out = os.environ.get("DESIGN_BENCH_OUT")
    if out:
        np.savez(Path(out) / f"{kind}{'-probe' if PROBE_ONLY else ''}-from{first}.npz", sds=np.array(sds),
                 targets=np.array(d.targets), scales=np.array(scales_drawn), first=first)


def _kept(kind: str) -> tuple[np.ndarray, np.ndarray]:
    """The realised sds (n, t) and drawn scales (n, 3) mm of every machine kept for ``kind`` (:func:`_keep`), in machine order (where a process
    stopped early, its range ends there: every machine is an independent draw of the population, so the kept ones
    are a sample of it still; the ranges are printed)."""
    parts = sorted((np.load(p) for p in Path(os.environ["DESIGN_BENCH_OUT"]).glob(
        f"{kind}{'-probe' if PROBE_ONLY else ''}-from*.npz")), key=lambda z: int(z["first"]))
    out, scales, ranges = np.zeros((0, len(parts[0]["targets"]))), np.zeros((0, len(SCALES))), []
    for z, after in zip(parts, [int(z["first"]) for z in parts[1:]] + [None]):
        first = int(z["first"])
        k = len(z["sds"]) if after is None else min(len(z["sds"]), max(after - first, 0))
        out, scales = np.vstack([out, z["sds"][:k]]), np.vstack([scales, z["scales"][:k]])
        ranges.append(f"{first}–{first + k - 1}")
    print(f"  machines kept: {', '.join(ranges)}")
    return out, scales


def given_scale(d, sds: np.ndarray, scales: np.ndarray) -> None:
    """Per target, the machines' realised sds against the check's at the same discrepancy scale: the check run again
    (its scales stratified), each target's sd fitted by a quadratic in the scale it follows most closely over the
    check's machines, and the machines' mean residual from that fit (± its standard error, and relative to the
    mean sd): zero where the bench and the check simulate one population, whatever luck either had in its scales."""
    goal = d.goal.targets
    planner = reporting_planner(d.campaign, d.candidates, {q: g for q, g in zip(d.targets, goal) if np.isfinite(g)},
                                instruments=d.instruments)
    pre = preposterior(planner, d.runs, seed=0, taught=taught(d.instruments), targets=goal)
    used = [i for i in SESSION if i in {r.instrument for r in d.runs}]  # the check's scales, in its order
    cols = [list(SCALES).index(i) for i in used]
    print("  given the scale: the machines' mean sd less the check's at their scale")
    for j, q in enumerate(d.targets):
        r = [abs(np.corrcoef(pre.sd[:, j], pre.scales[:, k])[0, 1]) for k in range(len(used))]
        k = int(np.nanargmax(r))
        fit = np.polyfit(pre.scales[:, k], pre.sd[:, j], 2)
        res = sds[:, j] - np.polyval(fit, scales[:, cols[k]])
        print(f"  {q:<12} {used[k]:>8} (r = {r[k]:.2f}): {res.mean():+.3g} ± {res.std(ddof=1) / np.sqrt(len(res)):.2g} "
              f"({res.mean() / sds[:, j].mean():+.1%})")


def main(n: int) -> None:
    for kind in TYPES:
        t0 = time.perf_counter()
        d, relaxed, left = _cached(kind, design_for)
        t_design = time.perf_counter() - t0
        c = measured(d)
        rng = np.random.default_rng(1)
        sds, scales_drawn = [], []
        for i in range(n if not MERGE else 0):
            truth, sigmas = draw_machine(c, rng)
            syn = simulate(c, truth, sigmas, rng)
            if i < FIRST:  # another process's machine: drawn and simulated only, to keep the random stream
                continue
            scales_drawn.append([sigmas[s] for s in SCALES])
            sds.append(realised_sd(syn, d.targets, data_of(c)))
            if i < AGAINST_DRAWS:  # the closed form against the sampler's draws of the same posterior
                s = api.sample(syn, sampler="exact", seed=1, data=data_of(c)).summary["sd"]
                off = max(abs(float(s[q]) / v - 1.0) for q, v in zip(d.targets, sds[-1]))
                print(f"  machine {i + 1}: the draws' sds within {off:.2%} of the exact posterior's", flush=True)
            if (i + 1) % 5 == 0:
                _keep(kind, d, FIRST, sds, scales_drawn)
                print(f"  {kind}: machine {i + 1}, {time.perf_counter() - t0:.0f} s", flush=True)
        if sds:
            _keep(kind, d, FIRST, sds, scales_drawn)
        sds, scales = _kept(kind) if MERGE else (np.array(sds), np.array(scales_drawn))
        k = d.check.kinematics
        runs = {i: sum(r.instrument == i for r in d.runs) for i in ("ballbar", "probe", "rtest")}
        print(f"\n{kind}{' (probe only)' if PROBE_ONLY else ''}: {len(d.runs)} runs ("
              + ", ".join(f"{v} {i}" for i, v in runs.items() if v) + f"), {d.total_minutes:.0f} min, "
              f"{d.rounds} round(s), designed in {t_design:.0f} s; {len(sds)} machines from the priors through the "
              f"{default_kinematic_model(c.machine)} ({time.perf_counter() - t0:.0f} s)")
        print(f"  design's check through the {k.model}: {k.through} (misfit {k.misfit_um:.3g} µm, threshold "
              f"{k.threshold_um:.3g} µm)")
        print(f"  not determined by the catalogue: {', '.join(left) or 'none'}")
        if relaxed:
            print("  relaxed (the catalogue cannot reach 3″/5 µm): " +
                  ", ".join(f"{q} → {v:.3g}" for q, v in relaxed.items()))
        for r, m in zip(d.runs, d.minutes):
            if r.instrument != "ballbar":
                print(f"  {r.label}: {m:.1f} min")
        share_table(d, sds)
        print(f"  promise: each target met in at least {PROMISE:.0%} of machines", flush=True)
        given_scale(d, sds, scales)


if __name__ == "__main__":
    main(int(next((a for a in ARGS if a.isdigit()), 50)))
