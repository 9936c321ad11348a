"""Measuring programs (``ncgen``, :mod:`mtmcal_bayes.io.chain_programs`): one path for every machine.

Each program of a demo machine is read back and its commanded positions are put through the nominal chain
(machines/chain.py, no deviations), an implementation independent of the pattern code that wrote them: a ball-bar
program holds the bar length at every block of its arc, a probe program indexes the run's angles and probes the
sphere from five directions at the stated distances.  The thesis machine's programs (its format, Fig 4.30(a)) are
checked against Tables 2.2/2.3 in ``tests/test_thesis_programs.py``; selection, planned runs and refusals are
checked here on every built-in type.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.campaign import ProbeRun, Run
from mtmcal_bayes.io.chain_programs import ballbar_program, probe_program
from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, builtin_description, demo_campaign
from mtmcal_bayes.io.nc_axes import axis_letters, read_axis_blocks
from mtmcal_bayes.machines.chain import Chain
from mtmcal_bayes.machines.patterns import placement_commands, tool_home
from tests.variants import probe_only, sections_dropped

#: the built-in types with a demo campaign in the generic format ([[probe.runs]], W-ball positions): their programs
#: are in the engine's format, read back through the chain
DEMOS = [t for t in BUILTIN_TYPES if demo_campaign(t) is not None]
#: decimals of the programs checked to 1e-9 mm (the default 4 rounds each word to 0.05 µm)
EXACT = 10


def _campaign(machine):
    return mb.load_campaign(demo_campaign(machine))


def _commands(blocks, letters) -> dict:
    """{letter: (k,)} of blocks, mm and rad (the chain's units)."""
    return {a: np.array([b.position[a] for b in blocks]) * (1.0 if a in "XYZ" else np.pi / 180.0)
            for a in letters}


def _bar_lengths(campaign, run, blocks) -> np.ndarray:
    """The nominal distance (k,) mm between tool ball and W ball at each block, through the chain with no
    deviations; the W ball placed where the tool ball is at the placement pose (its mount)."""
    desc = campaign.machine.description
    chain = Chain(desc, [])
    bb = campaign.ballbar
    tool = tool_home(desc, bb.setups[run.setup].R_B)
    q = _commands(blocks, axis_letters(desc))
    q0 = placement_commands(desc, length=bb.setups[run.setup].R_B, ball=bb.mounts[run.mount].position)
    w0 = chain.work_frame(chain.tool_point(tool[None, None, :], q0, {}), q0, {})
    T = chain.tool_point(np.broadcast_to(tool, (1, len(blocks), 3)), q, {})
    W = chain.work_point(np.broadcast_to(w0, (1, len(blocks), 3)), q, {})
    return np.linalg.norm(T - W, axis=-1)[0]


@pytest.mark.parametrize("machine", DEMOS)
def test_each_ballbar_program_holds_the_bar_length_over_the_runs_arc(machine):
    c = _campaign(machine)
    desc = c.machine.description
    letters = axis_letters(desc)
    for run in c.ballbar.runs:
        blocks = read_axis_blocks(ballbar_program(c, run, decimals=EXACT), letters)
        arc = [b for b in blocks if b.motion == "G01"]
        assert len(arc) == len(run.arc_deg)
        assert np.max(np.abs(_bar_lengths(c, run, arc) - c.ballbar.length)) < 1e-9, run.label
        K = run.pattern[0]
        assert np.array_equal(np.round([b.position[K] for b in arc], 9), run.arc_deg)
        for a in set(letters[3:]) - {K}:  # the held axes: positioned before the arc, still through it
            held = (run.hold_deg or {}).get(a, 0.0)
            assert blocks[0].position[a] == held and all(b.position[a] == held for b in arc)
        assert blocks[0].position[K] == run.arc_deg[0] and blocks[1].position == arc[0].position  # start point
        # as written (4 decimals): each linear word rounded by <= 0.05 µm, the angles exact
        printed = [b for b in read_axis_blocks(ballbar_program(c, run), letters) if b.motion == "G01"]
        assert np.max(np.abs(_bar_lengths(c, run, printed) - c.ballbar.length)) <= np.sqrt(3) * 0.5e-4


@pytest.mark.parametrize("machine", DEMOS)
def test_each_probe_program_indexes_the_runs_angles_and_probes_the_sphere(machine):
    c = _campaign(machine)
    desc = c.machine.description
    letters = axis_letters(desc)
    chain = Chain(desc, [])
    touch, clearance, overtravel = 12.0, 4.0, 1.5
    for run in c.probe.runs:
        text = probe_program(c, run, touch_radius_mm=touch, clearance_mm=clearance, overtravel_mm=overtravel,
                             decimals=EXACT)
        blocks = read_axis_blocks(text, letters)
        index = [b for b in blocks if set(b.words) <= set(letters[3:])]
        assert len(index) == run.positions
        for a in letters[3:]:
            want = np.degrees(run.angles.get(a, np.zeros(run.positions)))
            assert np.allclose([b.position[a] for b in index], want, atol=1e-9, rtol=0)
        stylus = tool_home(desc, c.probe.styli[run.stylus])
        q = _commands(blocks, letters)
        gap = (chain.tool_point(np.broadcast_to(stylus, (1, len(blocks), 3)), q, {})
               - chain.work_point(np.broadcast_to(run.sphere, (1, len(blocks), 3)), q, {}))[0]
        probes = [i for i, b in enumerate(blocks) if b.motion == "G31"]
        assert len(probes) == 5 * run.positions
        for i in probes:
            assert abs(np.linalg.norm(gap[i]) - (touch - overtravel)) < 1e-9
            assert abs(np.linalg.norm(gap[i - 1]) - (touch + clearance)) < 1e-9
            # the skip move heads for the centre: the angle between the two gaps below 1e-10 rad (the program's 10
            # decimals on commands of a few hundred mm and degrees round them at ~1e-12 relative)
            sine = np.linalg.norm(np.cross(gap[i], gap[i - 1])) / (np.linalg.norm(gap[i]) * np.linalg.norm(gap[i - 1]))
            assert sine < 1e-10
        for p in range(run.positions):  # five directions that fix a sphere's centre: they span space
            dirs = gap[probes[5 * p:5 * p + 5]]
            assert np.linalg.matrix_rank(dirs, tol=1e-6) == 3


def test_a_planned_run_gets_its_program_without_readings():
    c = _campaign("trunnion")
    text = ballbar_program(c, Run("CT", "T2", "W1", hold_deg={"A": -30.0}), feed=800)
    arc = [b for b in read_axis_blocks(text, ("X", "Y", "Z", "A", "C")) if b.motion == "G01"]
    assert len(arc) == 72 and all(b.position["A"] == -30.0 for b in arc) and "F800" in text
    run = c.probe.runs[0]
    planned = ProbeRun("p", run.stylus, run.sphere, run.angles, np.zeros((0, run.positions, 3)))
    assert probe_program(c, planned) == probe_program(c, run).replace("touch-probe run sphere", "touch-probe run p")


def test_the_cli_writes_a_pattern_run_and_probe_program(run_cli, tmp_path):
    out = tmp_path / "ar.nc"
    code, _, err = run_cli("ncgen", "AR", "--machine", "trunnion", "--arc-deg", "-30", "30", "--step-deg", "5",
                           "--hold", "C=90", "--feed", "500", "-o", out)
    assert code == 0, err
    arc = [b for b in read_axis_blocks(out.read_text(), "XYZAC") if b.motion == "G01"]
    assert [b.position["A"] for b in arc] == list(np.arange(-30.0, 31.0, 5.0))
    assert {b.position["C"] for b in arc} == {90.0}
    code, text, err = run_cli("ncgen", "--run", "7", "--machine", "trunnion")
    assert code == 0 and "held: A -45 deg" in text, err
    code, text, err = run_cli("ncgen", "--probe", "sphere", "--machine", "head-head")
    assert code == 0 and text.count("\nG31 ") == 5 * 9, err


@pytest.mark.parametrize("argv, key", [
    (["AQ"], "PATTERN: 'AQ' is not a pattern"),
    (["BR"], "PATTERN: 'BR': B is not a rotary axis of this machine"),
    (["AR", "--arc-deg", "-150", "0"], "--arc-deg: A reaches -150..0 deg, beyond its travel [-120, 30]"),
    (["CR", "--hold", "A=50"], "--hold: A at 50 deg, beyond its travel"),
    (["AR", "--hold", "B=3"], "--hold: B is not a held rotary axis of AR"),
    (["--run", "9"], "--run: the campaign has 8 ball-bar runs"),
    (["--probe", "x"], "--probe: no probe run 'x'"),
    (["AR", "--x0", "1", "--z0", "2"], "--x0/--y0/--z0: not an option of this machine's program format"),
    (["AR", "-n", "10"], "-n: not an option of this machine's program format"),
    (["AR", "--R-B-mm", "300"], "--R-B-mm: not an option of this machine's program format"),
])
def test_bad_input_is_one_line_and_writes_nothing(run_cli, tmp_path, argv, key):
    out = tmp_path / "out.nc"
    code, text, err = run_cli("ncgen", *argv, "--machine", "trunnion", "-o", out)
    assert code == 2 and len(err.strip().splitlines()) == 1 and key in err, err
    assert not out.exists() and text == ""


def test_options_a_format_takes_are_refused_with_a_probe_run(run_cli):
    """The thesis machine's format options (R_B_mm, start, n) are a ball-bar program's: with a probe run, refused."""
    code, _, err = run_cli("ncgen", "--probe", "1", "--machine", "head-head", "-n", "5")
    assert code == 2 and "-n: not an option of this machine's program format" in err, err
    code, _, err = run_cli("ncgen", "--probe", "1", "-n", "5")
    assert code == 2 and "-n: an option of a ball-bar program, not of a probe run's" in err, err


def _demo_text(machine) -> str:
    """The TOML text of ``machine``'s demo campaign (the thesis machine's: the built-in thesis campaign)."""
    from mtmcal_bayes.datasets import builtin_campaign_text

    path = demo_campaign(machine)
    if path is None:
        return builtin_campaign_text()[0]
    with open(path, encoding="utf-8") as f:
        return f.read()


@pytest.mark.parametrize("machine", DEMOS)
def test_ncgen_on_a_campaign_without_what_the_option_needs_is_one_line_naming_file_and_key(run_cli, tmp_path,
                                                                                           machine):
    """Issue 42, defect 6: ``--probe`` without ``[probe]``, ``--run`` without ball-bar runs, a pattern without
    ``[ballbar]``: one line naming the file and the key, exit 2, nothing written; the instrument the campaign has
    still gets its programs."""
    text = _demo_text(machine)
    no_probe, no_ballbar = tmp_path / "no-probe.toml", tmp_path / "no-ballbar.toml"
    no_probe.write_text(sections_dropped(text, "probe", "truth.probe"), encoding="utf-8")  # its truth too
    no_ballbar.write_text(probe_only(text), encoding="utf-8")
    pattern = mb.load_campaign(demo_campaign(machine)).ballbar.runs[0].pattern
    for argv, path, key in ((["--probe", "1"], no_probe, "probe.runs"), (["--run", "1"], no_ballbar, "ballbar.runs"),
                            ([pattern], no_ballbar, "ballbar.setups")):
        out = tmp_path / "out.nc"
        code, stdout, err = run_cli("ncgen", *argv, path, "-o", out)
        assert code == 2 and len(err.strip().splitlines()) == 1, err
        assert f"{path}: {key}: " in err and "internal error" not in err, err
        assert not out.exists() and stdout == ""
    for argv, path in ((["--run", "1"], no_probe), (["--probe", "1"], no_ballbar)):
        code, stdout, err = run_cli("ncgen", *argv, path)
        assert code == 0 and stdout.rstrip().endswith("M30"), err


@pytest.mark.parametrize("machine", BUILTIN_TYPES)
def test_ncgen_run_counts_the_planned_runs_after_the_measured_ones(run_cli, tmp_path, machine):
    """A designed campaign's planned runs get programs by number (as saved: the measured runs, then the planned
    ones in measuring order), the same program a measured run at that geometry gets."""
    import re

    text = sections_dropped(_demo_text(machine), "probe", "truth")
    # a planned run has no readings, so no traces and no reading rejected for it
    text = "\n".join(ln for ln in text.splitlines() if not ln.startswith(("alternative_", "trace_"))) + "\n"
    planned = tmp_path / "planned.toml"
    planned.write_text(re.sub(r"^(e[xyz]_um = \[.*\]\n)+", "planned = true\nrepeats = 3\n", text, flags=re.M),
                       encoding="utf-8")
    measured = tmp_path / "measured.toml"
    measured.write_text(text, encoding="utf-8")
    c = mb.load_campaign(planned)
    assert not c.ballbar.runs and len(c.ballbar.planned) == len(mb.load_campaign(measured).ballbar.runs)
    n = len(c.ballbar.planned)
    code, program, err = run_cli("ncgen", "--run", n, planned)
    assert code == 0, err
    code, same, err = run_cli("ncgen", "--run", n, measured)
    assert code == 0 and "G01 " in program and program.replace("planned.toml", "measured.toml") == same, err
    code, _, err = run_cli("ncgen", "--run", n + 1, planned)
    assert code == 2 and f"--run: the campaign has {n} ball-bar runs" in err, err


def test_ncgen_on_a_thesis_campaign_without_runs_writes_from_its_setups_and_probe_runs(run_cli, tmp_path):
    """The thesis machine's programs need its set-ups and mounts only: a campaign with no ball-bar runs yet gets
    them, and its probe runs' too."""
    from mtmcal_bayes.datasets import builtin_campaign_text

    text = sections_dropped(builtin_campaign_text()[0], "ballbar.runs")
    path = tmp_path / "new.toml"
    path.write_text("\n".join(ln for ln in text.splitlines() if not ln.startswith("alternative_reason")),
                    encoding="utf-8")
    code, program, err = run_cli("ncgen", "BX", path)
    code0, builtin, _ = run_cli("ncgen", "BX")
    assert code == code0 == 0 and program == builtin, err
    code, program, err = run_cli("ncgen", "--probe", "1", path)
    assert code == 0, err
    # its C-axis run is a probe run like any other's: by hand, the sphere at R_C 100 mm and 64.838 mm above the
    # table turned by C, the short stylus' ball centre 382.95 − 3 mm (its radius) below the B centre
    centres = np.array(re.findall(r"sphere centre at X(\S+) Y(\S+) Z(\S+)\)", program), dtype=float)
    C = np.radians([0.0, 90.0, 180.0, 270.0])
    np.testing.assert_allclose(centres, np.column_stack([100 * np.cos(C), 100 * np.sin(C),
                                                         np.full(4, 64.838 + 379.95)]), atol=1e-4)


@pytest.mark.parametrize("machine", [t for t in BUILTIN_TYPES
                                     if any(a.work_side for a in builtin_description(t).rotary_axes)])
def test_a_pattern_without_a_run_defaults_to_a_mount_its_axis_moves(machine):
    """``ncgen <K>X`` of a workpiece-side axis K with no run of its own: the default mount is one whose W ball K
    carries round (off K's line), so the linear axes follow it; a ball on K's line would leave them still (the
    vertical turn-mill's first mount sits on the C axis)."""
    from mtmcal_bayes.io.machine_reader import description_of

    c = mb.load_campaign(demo_campaign(machine))
    desc = description_of(c.machine)
    letters = axis_letters(desc)
    work = [a.letter for a in desc.rotary_axes if a.work_side]
    for K in work:
        assert not any(r.pattern == K + "X" for r in c.ballbar.runs)
        arc = [b for b in read_axis_blocks(mb.ncgen(K + "X", campaign=c), letters) if b.motion == "G01"]
        xyz = np.array([[b.position[a] for a in "XYZ"] for b in arc])
        assert np.ptp(xyz, axis=0).max() > 1.0, (machine, K)

