"""One sensitivity table on every machine (SPEC §19, the generalised thesis Tables 2.4–2.6): the thesis campaign and
every built-in type's demo go through the same function.

The oracle of the numbers is written here: each column is the central difference of the eccentricities the
simulator predicts (``predict_truth``: a truth naming one deviation or one nuisance term of one owner) for the
table's own campaign, in µm per ″ or per µm.  It checks what the table adds to its model — which run each row is,
which parameter each column is (the owners of the nuisance terms), the units — independently of the table's code.
The placement rule (the mount and held axes of the campaign's first run of each axis, a workpiece-side axis' W ball
off its line, the campaign format's own restrictions) is checked against the campaigns' runs, and on the thesis
campaign against Tables 2.2/2.3's geometry (B patterns at R_C = 0, C patterns at R_C > 0).
"""

from __future__ import annotations

import copy
from pathlib import Path

import numpy as np
import pytest

from mtmcal_bayes import units
from mtmcal_bayes.api import campaign_of
from mtmcal_bayes.campaign import Mount, Truth
from mtmcal_bayes.errors import InputError
from mtmcal_bayes.io.campaign_reader import deviation_quantities
from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, demo_campaign, description_of
from mtmcal_bayes.machines.patterns import DIRECTIONS
from mtmcal_bayes.parameters import MOUNT_NUISANCE, SETUP_NUISANCE
from mtmcal_bayes.simulation import predict_truth, sensitivity_table
from mtmcal_bayes.simulation.sensitivity import table_campaign

TYPES = tuple(BUILTIN_TYPES)  # the thesis machine (integrex-i200) first
#: central-difference step of the oracle, display units (″ or µm): not the table's own step (1)
STEP = 0.5
#: agreement, µm per ″ or per µm: the oracle's truncation error is O(STEP²) of third derivatives (≲ 1e-9 here) and
#: the table rounds |values| below 5e-7 to zero
TOL = 1e-6


@pytest.fixture(scope="module", params=TYPES)
def case(request):
    c = campaign_of(demo_campaign(request.param))
    return request.param, c, sensitivity_table(c)


def _first_run_of_each_axis(c) -> dict:
    out = {}
    for run in c.ballbar.runs:
        out.setdefault(run.pattern[0], run)
    return out


def test_rows_and_columns_are_the_machines(case):
    """Every pattern of every rotary axis of the machine with both its components; every deviation the machine names
    (the thesis' 13 by its names, a described machine's generated ISO symbols) and the nuisance bases."""
    name, c, df = case
    desc = description_of(c.machine)
    rows = {r.split()[0] for r in df.index}
    assert rows == {a.letter + d for a in desc.rotary_axes for d in DIRECTIONS}
    assert len(df) == 2 * len(rows) and all(df.index.str.split().str[0].value_counts() == 2)
    devs = [col for col in df.columns if col not in SETUP_NUISANCE and col not in MOUNT_NUISANCE]
    assert list(df.columns[len(devs):]) == [*SETUP_NUISANCE, *MOUNT_NUISANCE]
    if name == "integrex-i200":
        assert {"dx_BT", "alpha_XB", "beta_CZ", "gamma_XY"} <= set(devs) and len(devs) == 13
    else:
        assert all(d.startswith("E_") for d in devs) and "E_C0X" in devs
    assert df.attrs["model"] == ("htm-thesis" if name == "integrex-i200" else "chain")
    assert (df != 0).to_numpy().sum() > len(df)  # not an empty table


def test_placement_is_the_first_run_of_each_axis(case):
    """Each axis' patterns are measured on the campaign's first set-up at the mount and held positions of its first
    run of that axis (every built-in campaign's first runs have their W ball off a workpiece-side axis' line); on
    the thesis campaign that is the geometry of Tables 2.2/2.3."""
    name, c, _ = case
    t = table_campaign(c)
    first = _first_run_of_each_axis(c)
    setup = next(iter(c.ballbar.setups))
    assert [r.setup for r in t.ballbar.runs] == [setup] * len(t.ballbar.runs)
    for run in t.ballbar.runs:
        assert (run.mount, run.hold_deg) == (first[run.pattern[0]].mount, first[run.pattern[0]].hold_deg), run.pattern
    if name == "integrex-i200":
        r_c = {run.pattern[0]: t.ballbar.mounts[run.mount].R_C for run in t.ballbar.runs}
        assert r_c["B"] == 0 and r_c["C"] > 0
        assert [run.pattern[0] for run in t.ballbar.runs] == ["B"] * 6 + ["C"] * 6  # Tables 2.2/2.3's order


def _oracle_column(c, model: str, group: str, base: str, owner: str | None, kind: str) -> np.ndarray:
    """(m,) µm per display unit: central difference of the predicted eccentricities in one parameter."""
    step = units.to_internal(STEP, "arcsec" if kind == "angle" else "um")

    def truth(v: float) -> Truth:
        if group == "deviation":
            return Truth(deviations={base: v})
        return Truth(**{group + "s": {owner: {base: v}}})

    _, plus = predict_truth(c, truth(step), model)
    _, minus = predict_truth(c, truth(-step), model)
    return units.from_internal((plus - minus) / (2 * STEP), "um")


def test_every_column_is_the_simulators_derivative(case):
    """Column by column, the table equals the central difference of ``predict_truth`` on the table's campaign: the
    deviations, and each nuisance term of the set-up and mount each row was measured with (the others read 0)."""
    _, c, df = case
    t = table_campaign(c)
    model = df.attrs["model"]
    obs, _ = predict_truth(t, Truth(), model)
    labels = [f"{k.pattern} {k.component}" for k in obs.keys]
    assert labels == list(df.index)
    worst = 0.0
    for d, q in deviation_quantities(c.machine).items():
        col = _oracle_column(t, model, "deviation", d, None, q.kind)
        col[np.abs(col) < 5e-7] = 0.0
        worst = max(worst, float(np.abs(df[d].to_numpy() - col).max()))
    setup = t.ballbar.runs[0].setup
    for base, q in SETUP_NUISANCE.items():
        col = _oracle_column(t, model, "setup", base, setup, q.kind)
        col[np.abs(col) < 5e-7] = 0.0
        worst = max(worst, float(np.abs(df[base].to_numpy() - col).max()))
    for mount in {r.mount for r in t.ballbar.runs}:
        rows = np.array([k.mount == mount for k in obs.keys])
        for base, q in MOUNT_NUISANCE.items():
            col = _oracle_column(t, model, "mount", base, mount, q.kind)
            col[np.abs(col) < 5e-7] = 0.0
            assert np.all(col[~rows] == 0), (mount, base)  # another mount's rows do not see it
            worst = max(worst, float(np.abs(df[base].to_numpy()[rows] - col[rows]).max()))
    assert worst < TOL, worst


@pytest.mark.parametrize("machine", TYPES[1:])
def test_first_order_model_is_the_chains(machine):
    """``linear`` on a described machine is the chain's first order: the same table (before, its complex step went
    through a model that dropped the imaginary part, and the table was all zeros)."""
    c = campaign_of(demo_campaign(machine))
    lin, chain = sensitivity_table(c, "linear"), sensitivity_table(c, "chain")
    assert lin.attrs["model"] == "linear" and (lin != 0).to_numpy().any()
    assert np.abs(lin.to_numpy() - chain.to_numpy()).max() < 1e-9


def _trunnion_with_mount_on_c_line(move_c_runs: bool, keep_w1: bool):
    """The trunnion demo with a mount ``axis`` on the C axis' line (C turns about Z through (0, 0, -50) at A = 0)
    placed first, the C runs moved onto it; without W1 (``keep_w1`` False) every run is on it."""
    c = copy.deepcopy(campaign_of(demo_campaign("trunnion")))
    bb = c.ballbar
    mounts = {"axis": Mount("axis", 0.0, 0.0, position=np.array([0.0, 0.0, 30.0]))}
    if keep_w1:
        mounts.update(bb.mounts)
    bb.mounts = mounts
    for run in bb.runs:
        if run.pattern[0] == "C" and move_c_runs or not keep_w1:
            run.mount = "axis"
    return c


def test_a_w_ball_on_the_swivelled_axis_line_is_passed_over():
    """Where the campaign's C runs have their W ball on the C line, the C patterns go to the first mount off it (the
    other axes at 0); the A patterns keep their first run's mount."""
    c = _trunnion_with_mount_on_c_line(move_c_runs=True, keep_w1=True)
    t = table_campaign(c)
    at = {run.pattern[0]: (run.mount, run.hold_deg) for run in t.ballbar.runs}
    assert at == {"A": ("W1", None), "C": ("W1", None)}
    df = sensitivity_table(c)
    assert np.isfinite(df.to_numpy()).all()
    assert df.attrs["geometry"].endswith("; the C patterns at mount W1 (its first run's W ball lies on the axis line)")


def test_no_mount_off_the_line_is_refused_by_name():
    """Every mount on the C line: one line naming the file and ``ballbar.mounts``, the axis and the mounts' radii."""
    c = _trunnion_with_mount_on_c_line(move_c_runs=True, keep_w1=False)
    with pytest.raises(InputError) as e:
        sensitivity_table(c)
    text = str(e.value)
    assert "ballbar.mounts" in text and "C patterns" in text and text.endswith("have axis R_C_mm = 0")
    assert len(text.splitlines()) == 1


@pytest.mark.parametrize("machine", ["trunnion", "head-head"])
def test_probe_only_campaign_is_refused_by_name(run_cli, machine):
    """A probe-only campaign (a controller's measuring cycle) has no ball-bar set-up: one line naming the file and
    ``ballbar.setups``, exit 2 (it was an internal error)."""
    f = Path(__file__).parent / "data" / "controller_cycles" / f"{machine}-cycle.toml"
    code, out, err = run_cli("sensitivity", str(f))
    assert code == 2 and not out.strip() and len(err.strip().splitlines()) == 1, (code, err)
    assert f"{machine}-cycle.toml: ballbar.setups:" in err and "Traceback" not in err


def test_an_axis_without_runs_takes_the_first_mount():
    """The trunnion demo without its A runs: the A patterns at its first mount, the other axes at 0, and the
    geometry line says so."""
    c = copy.deepcopy(campaign_of(demo_campaign("trunnion")))
    c.ballbar.runs = [run for run in c.ballbar.runs if run.pattern[0] != "A"]
    t = table_campaign(c)
    assert {(run.mount, run.hold_deg) for run in t.ballbar.runs if run.pattern[0] == "A"} == {("W1", None)}
    assert sensitivity_table(c).attrs["geometry"].endswith("; the A patterns at mount W1 (no run of the axis)")
