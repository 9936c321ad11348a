"""The kinematic chain of a described machine (SPEC §19): equal to Eq 2.10 as printed on the thesis machine,
invariant under a relabelling of the frame, its first order checked against finite differences, its patterns
those of thesis Tables 2.2/2.3 where they are the same bar."""

from __future__ import annotations

import copy
import dataclasses

import numpy as np
import pytest

from mtmcal_bayes import units
from mtmcal_bayes.api import campaign_of
from mtmcal_bayes.io.campaign_reader import parse_campaign
from mtmcal_bayes.io.machine_reader import builtin_description
from mtmcal_bayes.machines.patterns import pattern_commands as described_commands
from mtmcal_bayes.models import make_model
from mtmcal_bayes.models.ballbar import BallbarModel, ChainKernel
from mtmcal_bayes.plugins.thesis.kinematic import HTMModel
from mtmcal_bayes.parameters import ParameterSpace
from mtmcal_bayes.campaign import Run
from mtmcal_bayes.patterns import B_PATTERNS, COMPONENTS, PATTERNS
from mtmcal_bayes.plugins.thesis.pattern_tables import pattern_commands as thesis_commands
from mtmcal_bayes.plugins.thesis.translation import translated


@pytest.fixture(scope="module")
def thesis():
    return campaign_of(None)


def _every_pattern(thesis, cr_geometry: str = "RC-LB"):
    """The thesis campaign with a run of each of its 12 patterns at each set-up (its own mounts), no probe."""
    c = copy.deepcopy(thesis)
    c.ballbar.runs = [Run(p, s, "B" if p in B_PATTERNS else "C", {k: np.zeros(1) for k in COMPONENTS[p]})
                      for s in c.ballbar.setups for p in PATTERNS]
    c.ballbar.cr_geometry, c.probe = cr_geometry, None
    return c


@pytest.mark.parametrize("cr_geometry", ["RC-LB", "RC+LB"])
def test_chain_is_htm_literal_on_the_thesis_machine(thesis, cr_geometry):
    """Every one of the 12 patterns at both set-ups (CR in both of the thesis' geometries), all 13 deviations and
    every nuisance term at random sizes up to ~150 µm / 150″: the thesis machine's ``chain`` (the engine's chain on
    its campaign translated into W-ball positions, arcs and bar sides) equals htm-literal's eccentricities and
    traces to 1e-9 mm."""
    c = _every_pattern(thesis, cr_geometry)
    space = ParameterSpace.for_campaign(c)
    rng = np.random.default_rng(7)
    theta = rng.normal(size=(32, len(space))) * space.display_scale() * 50
    literal, chain = HTMModel(c, "htm-literal", space), make_model("chain", c, space)
    assert isinstance(chain.kernel, ChainKernel)  # the engine's chain, not the plug-in's Eq 2.10
    assert isinstance(literal, BallbarModel) and not isinstance(literal.kernel, ChainKernel)
    assert np.abs(chain.predict(theta) - literal.predict(theta)).max() < 1e-9
    for (_, a), (_, b) in zip(literal.traces(theta), chain.traces(theta)):
        assert np.abs(a - b).max() < 1e-9
    # the campaign's runs in the engine's commands (machines/patterns) and polar angles instead of the Tables' as
    # printed: the same eccentricities, to rounding
    engine = translated(c)
    engine.ballbar.run_commands = None
    by_engine = BallbarModel(engine, space)
    assert any(not np.array_equal(a.q[x], b.q[x]) for a, b in zip(by_engine.runs, chain.runs) for x in "XYZ")
    assert np.abs(by_engine.predict(theta) - literal.predict(theta)).max() < 1e-9
    # and it is not the thesis' own pivots: htm-thesis differs at these sizes
    assert np.abs(HTMModel(c, "htm-thesis", space).predict(theta) - literal.predict(theta)).max() > 1e-4


def test_chain_is_a_model_of_every_command(thesis):
    m = make_model("chain", thesis)
    assert m.name == "chain" and m.predict(np.zeros(len(m.space))).shape == (len(m.observations),)


@pytest.mark.parametrize("pattern,cr_geometry", [(p, "RC-LB") for p in PATTERNS] + [("CR", "RC+LB")])
def test_described_patterns_are_the_thesis_tables(pattern, cr_geometry):
    """The generalised pattern ``<K><d>`` on the thesis machine's description gives the commands of thesis Tables
    2.2/2.3; the thesis' BT, and its CR in the geometry of Fig 2.6, with the bar reversed (the T ball on the other
    side of the W ball, docs/machines.md)."""
    desc = builtin_description("integrex-i200")
    R_B, Z_C, R_C, L_B = 356.3945, 65.5348, 50.0, 100.0
    b = pattern[0] == "B"
    ball = np.array([0.0 if b else R_C, 0.0, Z_C])
    arc = np.linspace(0.0, 90.0, 91) if b else np.arange(0.0, 360.0, 5.0)
    reverse = pattern == "BT" or cr_geometry == "RC+LB"
    ours = described_commands(desc, pattern, length=R_B, ball=ball, bar=L_B, arc_deg=arc, reverse=reverse)
    ref = thesis_commands(pattern, R_B=R_B, Z_C=Z_C, R_C=R_C, L_B=L_B, angles_deg=arc, cr_geometry=cr_geometry)
    for axis in "XYZBC":
        assert np.allclose(ours.q[axis], getattr(ref, axis), atol=1e-9), axis
    assert np.allclose(np.cos(ours.psi), np.cos(ref.psi)) and np.allclose(np.sin(ours.psi), np.sin(ref.psi))


# ---------------------------------------------------------------- a relabelled frame
#: X -> Y, Y -> Z, Z -> X: a point (x, y, z) has new coordinates (z, x, y); the letters move with the axes
RELABEL = {"X": "Y", "Y": "Z", "Z": "X", "A": "B", "B": "C", "C": "A"}


def _vec(v):
    return [v[2], v[0], v[1]]


def _described_thesis(relabel: bool) -> str:
    """The thesis machine described (ISO names, motion squareness), ball bar and probe; relabelled if asked."""
    L = (lambda s: "".join(RELABEL.get(ch, ch) for ch in s.replace("(C1)", "@")).replace("@", "(C1)")) if relabel \
        else (lambda s: s)  # noqa: E731
    P = _vec if relabel else (lambda v: v)  # noqa: E731
    d = (lambda v: {"+X": "+Y", "+Y": "+Z", "+Z": "+X", "-X": "-Y", "-Y": "-Z", "-Z": "-X"}[v]) if relabel else \
        (lambda v: v)  # noqa: E731
    c1, c2 = ("ex", "ey") if relabel else ("ez", "ex")  # B's plane (z, x) becomes C's (x, y)
    k1, k2 = ("ey", "ez") if relabel else ("ex", "ey")  # C's plane (x, y) becomes A's (y, z)

    def run(pattern, setup, mount, comps):
        a, b = comps
        if relabel:  # the axis letter moves; R, T, A name directions about it and stay
            pattern = RELABEL[pattern[0]] + (RELABEL[pattern[1]] if pattern[1] in "XYZ" else pattern[1])
        return (f'[[ballbar.runs]]\npattern = "{pattern}"\nsetup = "{setup}"\nmount = "{mount}"\n'
                f"{a}_um = [0.0]\n{b}_um = [0.0]\n")
    return f'''format = "mtmcal-campaign/1"
[machine]
configuration = "{L("w-C'bZYXB(C1)-t")}"
[machine.axes.{L("C")}]
direction = "{d("+Z")}"
[machine.axes.{L("B")}]
direction = "{d("+Y")}"
[machine.spindle]
direction = "{d("-Z")}"
[ballbar]
length_mm = 100.0
accuracy_um = 0.5
[ballbar.setups.RB1]
R_B_mm = 356.3945
[ballbar.setups.RB2]
R_B_mm = 406.4608
[ballbar.mounts.B]
position_mm = {P([0.0, 0.0, 65.5348])}
[ballbar.mounts.C]
position_mm = {P([50.0, 0.0, 65.5348])}
{run("BX", "RB1", "B", (c1, c2))}{run("BY", "RB1", "B", (c1, c2))}{run("CR", "RB1", "C", (k1, k2))}
{run("CA", "RB1", "C", (k1, k2))}{run("CR", "RB2", "C", (k1, k2))}
[probe]
repeatability_um = 1.0
[probe.styli.S]
length_mm = 300.0
[[probe.runs]]
id = "table"
stylus = "S"
sphere_mm = {P([60.0, 0.0, 50.0])}
angles_deg = {{{L("C")} = [0.0, 90.0, 180.0, 270.0]}}
centres_mm = [[[0,0,0],[0,0,0],[0,0,0],[0,0,0]]]
[[probe.runs]]
id = "head"
stylus = "S"
sphere_mm = {P([0.0, 0.0, 150.0])}
angles_deg = {{{L("B")} = [0.0, 45.0, 90.0]}}
centres_mm = [[[0,0,0],[0,0,0],[0,0,0]]]
'''


def _mapped(name: str) -> str:
    """A deviation's or nuisance term's name in the relabelled frame (``E_X0C`` -> ``E_Y0A``, ``xT[RB1]`` ->
    ``yT[RB1]``)."""
    if name.startswith("E_"):
        inner = name.replace("(0C1)", "@")  # the spindle's own name stays
        return "".join(RELABEL.get(ch, ch) if i > 1 else ch for i, ch in enumerate(inner)).replace("@", "(0C1)")
    base, owner = name.split("[")
    return {"x": "y", "y": "z", "z": "x"}.get(base[0], base[0]) + base[1:] + "[" + owner


@pytest.fixture(scope="module")
def relabelled():
    a = parse_campaign(_described_thesis(False), "original.toml")
    b = parse_campaign(_described_thesis(True), "relabelled.toml")
    return a, b


def _solve_rounding(post, sigma) -> np.ndarray:
    """How far (p,) the closed-form posterior mean of ``post`` at ``sigma`` may move by rounding alone when its
    parameters are ordered otherwise (a relabelled frame), internal units.

    The solve is x_w = M⁻¹ b_w in prior-sd units (M = I + A_wᵀV⁻¹A_w, b_w = A_wᵀV⁻¹(y − c − Aμ0)); inverting M in
    floating point errs by up to cond(M)·ε·‖M⁻¹‖ in norm, so each mean may move by its prior sd times
    cond(M)·ε·‖M⁻¹‖·‖b_w‖ (on the demos 1e-5 to 1e-2 of its posterior sd; a mislabelled axis moves a mean by its
    whole sd or more)."""
    from mtmcal_bayes.inference.analytic import linearisation

    A, c = linearisation(post)
    prior = post.priors.priors[: post.p]
    s0, mu0 = np.array([q.sd for q in prior]), np.array([q.centre for q in prior])
    V = post.likelihood.variance_at(sigma)
    Aw = A * s0
    M = np.eye(len(s0)) + Aw.T @ (Aw / V[:, None])
    b_w = Aw.T @ ((post.likelihood.y - c - A @ mu0) / V)
    return s0 * np.linalg.cond(M) * np.finfo(float).eps * np.linalg.norm(np.linalg.inv(M), 2) * np.linalg.norm(b_w)


def test_relabelling_the_frame_changes_nothing(relabelled):
    """The same machine in a cyclically relabelled frame: the same ball-bar readings and probe readings (mapped) for
    the same (mapped) truth, and the same posterior of each mapped deviation (the exact posterior's sd to 1e-9
    relative, its mean to the rounding of the closed form's solve, :func:`_solve_rounding`), the same identifiable combinations."""
    from mtmcal_bayes.inference.analytic import gaussian_posterior
    from mtmcal_bayes.inference.log_posterior import LogPosterior
    from mtmcal_bayes.inference.identifiability import campaign_identifiability

    a, b = relabelled
    ma, mb_ = make_model("chain", a, data="both"), make_model("chain", b, data="both")
    assert sorted(_mapped(n) for n in ma.space.names) == sorted(mb_.space.names)
    order = [mb_.space.names.index(_mapped(n)) for n in ma.space.names]
    rng = np.random.default_rng(3)
    theta = rng.normal(size=(8, len(ma.space))) * ma.space.display_scale() * 30
    theta_b = np.zeros_like(theta)
    theta_b[:, order] = theta
    assert np.allclose(ma.predict(theta), _map_observations(mb_.predict(theta_b), b), atol=1e-9)

    # data from a truth, then the two exact posteriors at a fixed σ
    y = ma.predict(theta[0])
    from mtmcal_bayes.observations import with_run_values  # noqa: F401  (the values go in as readings below)
    pa = LogPosterior(a, "linear", data="both", sigma_model=units.to_internal(0.5, "um"))
    pb = LogPosterior(b, "linear", data="both", sigma_model=units.to_internal(0.5, "um"))
    pa.likelihood = pa.likelihood.with_means(y)
    pb.likelihood = pb.likelihood.with_means(_unmap_observations(y, b))
    ga, gb = gaussian_posterior(pa, units.to_internal(0.5, "um")), gaussian_posterior(pb, units.to_internal(0.5, "um"))
    deviations = [p.name for p in pa.space.parameters if p.group == "deviation"]
    rounding = _solve_rounding(pa, units.to_internal(0.5, "um"))
    for n in deviations:
        j = pb.space.names.index(_mapped(n))
        ma_, sa = ga.linear_combination({n: 1.0})
        mb2, sb = gb.linear_combination({pb.space.names[j]: 1.0})
        assert sb == pytest.approx(sa, rel=1e-9), n
        assert abs(mb2 - ma_) <= rounding[pa.space.names.index(n)], n
    ia, ib = campaign_identifiability(pa), campaign_identifiability(pb)
    assert sorted(_mapped(n) for n in ia.determined) == sorted(ib.determined)
    assert sorted(_mapped(n) for n in ia.undetermined) == sorted(ib.undetermined)
    wa = sorted(tuple(sorted((_mapped(k), round(v, 9)) for k, v in c.weights.items())) for c in ia.combinations)
    wb = sorted(tuple(sorted((k, round(v, 9)) for k, v in c.weights.items())) for c in ib.combinations)
    assert wa == wb


def _map_observations(y, campaign):
    """Observations of the relabelled campaign in the original's order and axes (components keep their order; probe
    readings' X, Y, Z of the relabelled frame are the original's Y, Z, X)."""
    y = np.array(y, copy=True)
    m = len(campaign.ballbar.runs) * 2
    probe = y[..., m:].reshape(y.shape[:-1] + (-1, 3))
    y[..., m:] = probe[..., [1, 2, 0]].reshape(y.shape[:-1] + (-1,))
    return y


def _unmap_observations(y, campaign):
    y = np.array(y, copy=True)
    m = len(campaign.ballbar.runs) * 2
    probe = y[..., m:].reshape(y.shape[:-1] + (-1, 3))
    y[..., m:] = probe[..., [2, 0, 1]].reshape(y.shape[:-1] + (-1,))
    return y


def test_first_order_model_is_the_chains_jacobian(relabelled):
    """``linear`` on a described machine: the chain's Jacobian at zero; it agrees with the chain to second order
    (a tenfold smaller step leaves a hundredfold smaller gap)."""
    a, _ = relabelled
    chain, linear = make_model("chain", a, data="both"), make_model("linear", a, data="both")
    rng = np.random.default_rng(5)
    step = rng.normal(size=len(chain.space)) * chain.space.display_scale() * 20
    gaps = [np.abs(chain.predict(s * step) - linear.predict(s * step)).max() for s in (1.0, 0.1)]
    assert gaps[1] < gaps[0] / 50
    assert dataclasses.is_dataclass(a.machine.description)


# ---------------------------------------------------------------- every built-in type, relabelled
def _relabel_letters(s: str) -> str:
    return "".join(RELABEL.get(ch, ch) for ch in s.replace("(C1)", "@").replace("(0C1)", "#")) \
        .replace("@", "(C1)").replace("#", "(0C1)")


def _relabel_document(doc: dict) -> dict:
    """A described campaign's TOML document in the cyclically relabelled frame: the description written out (a
    built-in's expanded), letters, directions, points, components and readings mapped."""
    import copy
    import tomllib

    from mtmcal_bayes.datasets import builtin_text

    doc = copy.deepcopy(doc)
    m = doc["machine"]
    if "description" in m:
        m.update(tomllib.loads(builtin_text(f"machines/{m.pop('description')}.toml")))
    flip = {"X": "Y", "Y": "Z", "Z": "X"}
    d = lambda v: v[0] + flip[v[1]] if isinstance(v, str) else _vec(v)  # noqa: E731
    m["configuration"] = _relabel_letters(m["configuration"])
    m["axes"] = {RELABEL[k]: {kk: (d(vv) if kk == "direction" else _vec(vv) if kk == "point_mm" else vv)
                              for kk, vv in a.items()} for k, a in m.get("axes", {}).items()}
    m["spindle"] = {k: (d(v) if k == "direction" else _vec(v)) for k, v in m["spindle"].items()}
    if "deviations" in m:
        m["deviations"] = [_mapped(x) for x in m["deviations"]]
    comp = {"ex_um": "ey_um", "ey_um": "ez_um", "ez_um": "ex_um"}
    if "ballbar" in doc:
        bb = doc["ballbar"]
        for mt in bb["mounts"].values():
            mt["position_mm"] = _vec(mt["position_mm"])
        for run in bb["runs"]:
            p = run["pattern"]
            run["pattern"] = RELABEL[p[0]] + (flip[p[1]] if p[1] in flip else p[1])
            for k in [k for k in run if k in comp]:
                run[comp[k] + "_new"] = run.pop(k)
            for k in [k for k in run if k.endswith("_new")]:
                run[k[:-4]] = run.pop(k)
            if "hold_deg" in run:
                run["hold_deg"] = {RELABEL[k]: v for k, v in run["hold_deg"].items()}
    if "probe" in doc:
        for run in doc["probe"]["runs"]:
            run["sphere_mm"] = _vec(run["sphere_mm"])
            run["angles_deg"] = {RELABEL[k]: v for k, v in run["angles_deg"].items()}
            run["centres_mm"] = [[_vec(c) for c in rep] for rep in run["centres_mm"]]
    if "truth" in doc:
        doc["truth"]["deviations"] = {_mapped(k.rsplit("_", 1)[0]) + "_" + k.rsplit("_", 1)[1]: v
                                      for k, v in doc["truth"]["deviations"].items()}
    return doc


@pytest.mark.parametrize("machine", ["vertical-turn-mill", "trunnion", "head-head"])
def test_each_built_in_type_relabelled_is_the_same_machine(machine):
    """The demo campaign of each built-in type in a cyclically relabelled frame (X→Y, Y→Z, Z→X, the letters of the
    axes with them): the same measurements (mapped), the same exact posterior of each mapped deviation (its sd to
    1e-9 relative, its mean to the rounding of the closed form's solve: the first order's, the exact sampler's
    target) and
    the same combinations."""
    import tomllib

    from mtmcal_bayes.datasets import builtin_text
    from mtmcal_bayes.inference.analytic import gaussian_posterior
    from mtmcal_bayes.inference.identifiability import campaign_identifiability
    from mtmcal_bayes.inference.log_posterior import LogPosterior
    from mtmcal_bayes.io.tomlio import dumps

    text = builtin_text(f"machines/{machine}-demo.toml")
    a = parse_campaign(text, "original.toml")
    b = parse_campaign(dumps(_relabel_document(tomllib.loads(text))), "relabelled.toml")
    sigma = units.to_internal(0.5, "um")
    pa = LogPosterior(a, "linear", data="both", sigma_model=sigma)
    pb = LogPosterior(b, "linear", data="both", sigma_model=sigma)
    assert sorted(_mapped(n) for n in pa.space.names) == sorted(pb.space.names)
    assert np.allclose(pa.likelihood.y, _map_observations(pb.likelihood.y, b), atol=1e-12)
    ga, gb = gaussian_posterior(pa, sigma), gaussian_posterior(pb, sigma)
    rounding = _solve_rounding(pa, sigma)
    for i, p in enumerate(pa.space.parameters):
        if p.group != "deviation":
            continue
        m1, s1 = ga.linear_combination({p.name: 1.0})
        m2, s2 = gb.linear_combination({_mapped(p.name): 1.0})
        assert s2 == pytest.approx(s1, rel=1e-9), p.name
        assert abs(m2 - m1) <= rounding[i], p.name
    ia, ib = campaign_identifiability(pa), campaign_identifiability(pb)
    assert sorted(map(_mapped, ia.determined)) == sorted(ib.determined)
    assert sorted(map(_mapped, ia.undetermined)) == sorted(ib.undetermined)
    wa = sorted(tuple(sorted((_mapped(k), round(v, 9)) for k, v in c.weights.items())) for c in ia.combinations)
    assert wa == sorted(tuple(sorted((k, round(v, 9)) for k, v in c.weights.items())) for c in ib.combinations)


def test_complex_step_first_order_against_finite_differences(relabelled):
    """The ``linear`` model of a described machine is the complex-step Jacobian of the chain; central finite
    differences (1 µm, 1″ steps) agree with it to their own truncation error, 1e-6 of the largest entry."""
    from mtmcal_bayes.models.jacobian import complex_step_jacobian
    from mtmcal_bayes.models import jacobian

    a, _ = relabelled
    for data in ("ballbar", "probe"):
        m = make_model("chain", a, data=data)
        J, F = complex_step_jacobian(m), jacobian(m)
        assert np.abs(J - F).max() <= 1e-6 * np.abs(J).max(), data
