"""The one ball-bar model (``models/ballbar.py``): its point table, parameter columns, fit and compensated commands
serve every kernel; the thesis' Eq 2.10 with its pivots is one kernel of it, the chain another."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from mtmcal_bayes.campaign import Run
from mtmcal_bayes.models import make_model
from mtmcal_bayes.models.ballbar import BallbarModel, ChainKernel
from mtmcal_bayes.parameters import ParameterSpace
from mtmcal_bayes.patterns import B_PATTERNS, COMPONENTS, PATTERNS, polar_angle
from mtmcal_bayes.plugins.thesis.kinematic import HTMModel, PivotsKernel
from mtmcal_bayes.plugins.thesis.pattern_tables import (
    pattern_commands as table_commands,
)


def _thesis_with(thesis, runs):
    c = copy.deepcopy(thesis)
    c.ballbar.runs, c.probe = runs, None
    return c


def _theta(space, n=16, size=50, seed=7):
    """Deviations and nuisance terms at random sizes up to ~``size`` µm / ″ (mm, rad)."""
    return np.random.default_rng(seed).normal(size=(n, len(space))) * space.display_scale() * size


def test_the_thesis_models_and_the_chain_are_one_model_on_one_table(thesis):
    """htm-literal, htm-thesis and the thesis machine's chain are the one model with three kernels: the same
    points (commands, tool lengths, dummy-sphere points and placements, setups and mounts, run slices) and the same
    parameter columns, to the bit."""
    models = [make_model("chain", thesis), HTMModel(thesis, "htm-literal"), HTMModel(thesis, "htm-thesis")]
    assert all(type(m) is BallbarModel for m in models)
    assert isinstance(models[0].kernel, ChainKernel)
    assert [m.kernel.name for m in models[1:]] == ["htm-literal", "htm-thesis"]
    assert all(isinstance(m.kernel, PivotsKernel) for m in models[1:])
    ref = models[0].points()
    for m in models[1:]:
        pts = m.points()
        assert pts.runs == ref.runs and set(pts.q) == set(ref.q)
        for a in ref.q:
            assert np.array_equal(pts.q[a], ref.q[a]), a
        for field in ("length", "dummy", "placement", "setup", "mount"):
            assert np.array_equal(getattr(pts, field), getattr(ref, field)), field
        for cols, ref_cols in ((pts.setup_cols, ref.setup_cols), (pts.mount_cols, ref.mount_cols)):
            assert cols.keys() == ref_cols.keys() and all(np.array_equal(cols[b], ref_cols[b]) for b in cols)


@pytest.mark.parametrize("cr_geometry", ["RC-LB", "RC+LB"])
def test_thesis_runs_are_evaluated_at_the_tables_as_printed(thesis, cr_geometry):
    """Every pattern of a thesis-format campaign is evaluated at the commands of Tables 2.2/2.3 and read at the
    polar angles its measured traces are read at (θ, θ + 180° for CR with the T ball inside), to the bit: the bits
    the published numbers were computed with (the chain's own commands equal them only to ~1e-13 mm)."""
    c = _thesis_with(thesis, [Run(p, "RB1", "B" if p in B_PATTERNS else "C", {k: np.zeros(1) for k in COMPONENTS[p]})
                              for p in PATTERNS])
    c.ballbar.cr_geometry = cr_geometry
    model = HTMModel(c, "htm-thesis")
    s, bb = c.ballbar.setups["RB1"], c.ballbar
    for run, planned in zip(bb.runs, model.runs):
        m = bb.mounts[run.mount]
        ref = table_commands(run.pattern, R_B=s.R_B, Z_C=m.Z_C, R_C=m.R_C, L_B=bb.length, cr_geometry=cr_geometry)
        for a in "XYZBC":
            assert np.array_equal(planned.q[a], getattr(ref, a)), (run.pattern, a)
        theta = ref.B if run.pattern in B_PATTERNS else ref.C
        assert np.array_equal(planned.psi, polar_angle(run.pattern, theta, cr_geometry)), run.pattern


def test_thesis_kernel_runs_on_the_engines_commands(thesis):
    """Runs the Tables do not give (a BR with C held at 30°, a BX with its bar reversed) take the engine's
    commands; the thesis' Eq 2.10 as printed evaluates them as the chain does, to 1e-9 mm, at deviations and
    nuisance terms up to ~150 µm / 150″, and the held and reversed runs read otherwise than the plain one
    (> 1 µm)."""
    def run(pattern, **kw):
        return Run(pattern, "RB1", "B" if pattern in B_PATTERNS else "C", {k: np.zeros(1) for k in COMPONENTS[pattern]},
                   **kw)

    runs = [run("BR"), run("BR", hold_deg={"C": 30.0}), run("BX"), run("BX", reversed=True), run("CR")]
    c = _thesis_with(thesis, runs)
    space = ParameterSpace.for_campaign(c)
    theta = _theta(space)
    literal, chain = HTMModel(c, "htm-literal", space), make_model("chain", c, space)
    bb = chain.campaign.ballbar
    assert [bb.run_commands(r, bb) is None for r in bb.runs] == [False, True, False, True, False]
    a, b = literal.predict(theta), chain.predict(theta)
    assert np.abs(a - b).max() < 1e-9
    rows = [[j for j, k in enumerate(chain.observations.keys) if k.run == i] for i in range(4)]
    assert np.abs(a[:, rows[1]] - a[:, rows[0]]).max() > 1e-3  # the W-ball offsets turned with C
    assert np.abs(a[:, rows[3]] - a[:, rows[2]]).max() > 1e-3


@pytest.mark.parametrize("model", ["chain", "htm-thesis"])
def test_replaced_commands_move_only_their_run(thesis, model):
    """Compensation's verification re-runs a run with other commands: the first CR run's X commands moved by
    δ = 10 µm move the T ball by δ along X, which its trace reads as ΔL = δ cos ψ (ψ the bar's direction): its ex
    by δ and its ey not, to second order δ²/L_B = 1e-6 mm (at zero deviations: with them, terms δ·e/L_B join); no
    other run moves at all, at any deviations."""
    m = make_model(model, thesis)
    i = next(k for k, r in enumerate(thesis.ballbar.runs) if r.pattern == "CR")
    theta = np.vstack([np.zeros(len(m.space)), _theta(m.space, n=3, size=20)])  # the first: no deviations
    before = m.predict(theta)
    q = m.runs[i].q
    m.replace_commands(i, dict(q, X=q["X"] + 0.010))
    after = m.predict(theta)
    comp = {k.component: j for j, k in enumerate(m.observations.keys) if k.run == i}
    others = [j for j, k in enumerate(m.observations.keys) if k.run != i]
    assert np.array_equal(after[:, others], before[:, others])
    assert after[0, comp["ex"]] - before[0, comp["ex"]] == pytest.approx(0.010, abs=1e-6)
    assert after[0, comp["ey"]] - before[0, comp["ey"]] == pytest.approx(0.0, abs=1e-6)


def test_eccentricities_are_what_predict_returns(thesis):
    """The per-run fits (r0, e_1, e_2 and the residual rms) carry the predicted eccentricities by component name; at
    zero deviations every trace is flat (rms and every coefficient below 1e-12 mm)."""
    m = make_model("chain", thesis)
    theta = _theta(m.space, n=3)
    pred = m.predict(theta)
    for i, fit in enumerate(m.eccentricities(theta)):
        for j, k in enumerate(m.observations.keys):
            if k.run == i:
                assert np.array_equal(fit.component(k.component), pred[:, j])
    for fit in m.eccentricities(np.zeros(len(m.space))):
        assert np.abs(fit.coef).max() < 1e-12 and fit.rms.max() < 1e-12
