"""Reading conventions on every machine (SPEC §17, issue 42: "reading conventions (a per-run map that any
machine's runs may carry)"): a described machine's runs may say how their offsets were read, as the thesis
campaign's do, and the engine reads them into its machine frame before any model sees them.

The reference of the round trip is the demo campaign itself: each run's offsets are re-expressed as a software
drawing its plot another way would report them (computed here from the run's frame, U and D, not by the code's
inverse), written with that reading, read back, and must give the demo's machine-frame observations to 1e-12 mm.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from mtmcal_bayes import api
from mtmcal_bayes.conventions import frame_directions, run_frame
from mtmcal_bayes.io import load_campaign, save_campaign
from mtmcal_bayes.observations import Observations
from tests.variants import demo_with_first_run_key

TYPES = ("trunnion", "vertical-turn-mill", "head-head")


def _swapped(frame) -> str:
    """The plot with the two axes of the run's plane swapped (a plane seen from the other side): a geometry string."""
    a, b = frame.axes
    return f"{frame.letter}0=+{b},{frame.letter}90=+{a}"


@pytest.mark.parametrize("machine", TYPES)
def test_offsets_read_another_way_give_the_same_machine_frame(machine, tmp_path):
    c = load_campaign(api.demo_campaign(machine))
    want = Observations.from_campaign(c)
    other = copy.deepcopy(c)
    for run in other.ballbar.runs:
        frame = run_frame(run, other.ballbar)
        run.convention = _swapped(frame)
        D = frame_directions(run.convention, frame)
        # e_m = U⁻¹ D e_r, so the software reports e_r = D⁻¹ U e_m (each repeat a column)
        e_m = np.vstack([run.repeats[k] for k in frame.components])
        e_r = np.linalg.solve(D, frame.basis @ e_m)
        run.repeats = {k: e_r[i] for i, k in enumerate(frame.components)}
    path = tmp_path / "read-otherwise.toml"
    save_campaign(other, path)
    assert 'convention = "' in path.read_text(encoding="utf-8")
    back = load_campaign(path)
    assert [r.convention for r in back.ballbar.runs] == [r.convention for r in other.ballbar.runs]
    got = Observations.from_campaign(back)
    assert got.labels == want.labels
    np.testing.assert_allclose(got.mean, want.mean, rtol=0, atol=1e-12)
    np.testing.assert_allclose(got.sd, want.sd, rtol=0, atol=1e-12)
    assert not np.allclose(np.concatenate([np.atleast_1d(r.mean(k)) for r in back.ballbar.runs for k in r.repeats]),
                           np.concatenate([np.atleast_1d(r.mean(k)) for r in c.ballbar.runs for k in r.repeats]))


def test_the_machine_reading_of_a_tangential_run_leads_by_the_bar_over_the_radius():
    """``"machine"``: the programmed position of a tangential pattern leads the C angle by atan(L_B / r), r the W
    ball's distance from the C axis line (the thesis' CT: atan(L_B/R_C)); on the vertical turn-mill's CT run,
    L_B = 100 mm and r = 50 mm."""
    c = load_campaign(api.demo_campaign("vertical-turn-mill"))
    bb = c.ballbar
    run = next(r for r in bb.runs if r.pattern == "CT")
    frame = run_frame(run, bb)
    D, U = frame_directions("machine", frame), frame.basis
    ball = bb.mounts[run.mount].position
    lead = math.atan2(bb.length, math.hypot(ball[0], ball[1]))
    for k in range(2):
        turned = math.atan2(U[k, 0] * D[k, 1] - U[k, 1] * D[k, 0], U[k] @ D[k])
        assert abs(abs(turned) - lead) < 1e-9, (k, math.degrees(turned), math.degrees(lead))


def test_a_reading_of_another_axis_is_refused_naming_the_run(tmp_path, run_cli):
    bad = tmp_path / "bad.toml"
    bad.write_text(demo_with_first_run_key("trunnion", 'convention = "B0=+X,B90=+Z"'), encoding="utf-8")
    code, out, err = run_cli("sample", str(bad), "--sampler", "exact", "--seed", "1")
    assert code == 2 and "Traceback" not in err
    line = err.strip().splitlines()[-1]
    assert "ballbar.runs[0].convention" in line and "names the B angle" in line, line


def _tables_frame(pattern: str, *, R_B: float, Z_C: float, R_C: float, L_B: float, cr_geometry: str):
    """The reading frame of thesis ``pattern`` written from Tables 2.2/2.3 alone (the reference the chain's frames
    are held to): components ``(ex, ez)`` / ``(ex, ey)``, basis rows the sample directions at 0° and 90° (B: φ →
    (sin φ, cos φ); C: ψ → (cos ψ, sin ψ), ψ = θ, θ + 180° for CR with its T ball inside the W ball) and the
    programmed directions from the Tables' commands about the arc's centre."""
    from mtmcal_bayes.conventions import PatternFrame
    from mtmcal_bayes.patterns import B_PATTERNS, COMPONENTS, polar_angle
    from mtmcal_bayes.plugins.thesis.pattern_tables import pattern_commands

    is_b = pattern in B_PATTERNS
    if is_b:
        basis = np.c_[np.sin(np.radians([0.0, 90.0])), np.cos(np.radians([0.0, 90.0]))]
    else:
        psi = polar_angle(pattern, np.radians([0.0, 90.0]), cr_geometry)
        basis = np.c_[np.cos(psi), np.sin(psi)]
    cmd = pattern_commands(pattern, R_B=R_B, Z_C=Z_C, R_C=R_C, L_B=L_B, angles_deg=np.array([0.0, 90.0, 180.0, 270.0]),
                           cr_geometry=cr_geometry)
    pts = np.c_[cmd.X, cmd.Z] if is_b else np.c_[cmd.X, cmd.Y]
    d = pts[:2] - 0.5 * (pts[0] + pts[2])
    programmed = d / np.linalg.norm(d, axis=1, keepdims=True)
    comps = COMPONENTS[pattern]
    return PatternFrame("B" if is_b else "C", comps, tuple(c[1].upper() for c in comps), basis, lambda: programmed)


@pytest.mark.parametrize("cr_geometry", ["RC-LB", "RC+LB"])
def test_the_chains_frames_read_the_thesis_patterns_as_its_tables_do(cr_geometry):
    """Every thesis pattern at both set-ups, on the thesis campaign read into the engine's terms (W balls from R_C
    and Z_C, arcs, the bar sides of BT and CR: plugins/thesis/translation.py): the frames its runs are read against
    (the chain's) give the reading matrices of frames written from Tables 2.2/2.3 in this test, under the thesis
    reading, the programmed one and a geometry string, to 1e-9 (the components matched by name: (ex, ez) in the
    thesis, (ez, ex) in the chain)."""
    from mtmcal_bayes.campaign import Run
    from mtmcal_bayes.conventions import frame_matrix
    from mtmcal_bayes.patterns import B_PATTERNS, COMPONENTS, PATTERNS
    from mtmcal_bayes.plugins.thesis.translation import reversed_patterns

    c = load_campaign(None)
    bb = c.ballbar
    bb.runs = [Run(p, s, "B" if p in B_PATTERNS else "C", {k: np.zeros(1) for k in COMPONENTS[p]})
               for s in bb.setups for p in PATTERNS]
    bb.cr_geometry, bb.reversed_patterns = cr_geometry, reversed_patterns(cr_geometry)
    for run in bb.runs:
        s, m = bb.setups[run.setup], bb.mounts[run.mount]
        own = _tables_frame(run.pattern, R_B=s.R_B, Z_C=m.Z_C, R_C=m.R_C, L_B=bb.length, cr_geometry=cr_geometry)
        chain = run_frame(run, bb)
        order = [chain.components.index(k) for k in own.components]
        geometry = "B0=+X,B90=+Z" if run.pattern in B_PATTERNS else "C0=-Y,C90=+X"
        for convention in ("thesis", "machine", geometry):
            np.testing.assert_allclose(frame_matrix(convention, chain)[np.ix_(order, order)],
                                       frame_matrix(convention, own), rtol=0, atol=1e-9,
                                       err_msg=f"{run.pattern}@{run.setup} {convention}")


@pytest.mark.parametrize("machine", ["thesis", *TYPES])
def test_a_campaign_built_in_python_reads_its_runs_as_the_read_one(machine):
    """A campaign built in Python from the parts of a read one (its ball bar without the frames, arcs and bar sides
    the reader gave it; the thesis' with a machine of no description, as a script writes it) reads every run as the
    read campaign does: the same machine-frame observations, to 1e-12 mm.  The thesis campaign reads its BX and BY
    runs otherwise than in the machine frame, so its frames are needed."""
    import dataclasses

    from mtmcal_bayes.campaign import Ballbar, Campaign, Machine
    from mtmcal_bayes.conventions import ConventionError
    from mtmcal_bayes.io.machine_reader import demo_campaign

    read = load_campaign(None) if machine == "thesis" else load_campaign(demo_campaign(machine))
    bb = read.ballbar
    if machine != "thesis":  # the demos read every run in the machine frame: read them as programmed instead
        for run in bb.runs:
            run.convention = "machine"
    fields = {f.name: getattr(bb, f.name) for f in dataclasses.fields(Ballbar)
              if f.name not in ("pattern_frames", "reversed_patterns", "pattern_arcs")}
    own = Machine() if machine == "thesis" else read.machine
    built = Campaign(machine=own, ballbar=Ballbar(**fields), source="<python>")
    a, b = Observations.from_campaign(read), Observations.from_campaign(built)
    assert a.keys == b.keys
    np.testing.assert_allclose(b.mean, a.mean, rtol=0, atol=1e-12)
    assert any(r.convention not in (None, "thesis") for r in bb.runs)
    plain = copy.deepcopy(built)
    plain.ballbar.pattern_frames = None  # without frames, a reading other than the machine frame's is refused
    with pytest.raises(ConventionError):
        Observations.from_campaign(plain)
