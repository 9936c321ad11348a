"""One ball-bar reader for every machine (SPEC §20, issue 42): the thesis campaign's set-ups, mounts and
``cr_geometry`` are its plug-in's keys in the engine's reader, and what its format had first — traces, a reading
chosen over another, a planned run's own bar — is read, saved and used on every built-in type.

The thesis' side of the same reader: tests/test_bad_inputs.py (its corpus of bad campaigns and traces),
test_reading_choice.py, test_planned_runs.py, and test_properties.py (traces simulated by ``htm-thesis``, an
independent model, read back through the chain's directions)."""

from __future__ import annotations

import dataclasses
import tomllib

import numpy as np
import pytest

from mtmcal_bayes import InputError, load_campaign, parse_campaign, save_campaign
from mtmcal_bayes.conventions import run_matrix
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.io.tomlio import dumps
from mtmcal_bayes.machines.patterns import components
from mtmcal_bayes.models.ballbar import ChainBallbarModel
from mtmcal_bayes.observations import Observations
from mtmcal_bayes.simulation.simulate import planned_as_runs
from mtmcal_bayes.units import ARCSEC

TYPES = ("trunnion", "vertical-turn-mill", "head-head")


def _demo(machine: str) -> dict:
    return tomllib.loads(open(demo_campaign(machine), encoding="utf-8").read())


def _loads(doc: dict, tmp_path, name: str = "c.toml"):
    path = tmp_path / name
    path.write_text(dumps(doc), encoding="utf-8")
    return load_campaign(path)


def _error(doc: dict, tmp_path) -> InputError:
    with pytest.raises(InputError) as info:
        _loads(doc, tmp_path, "bad.toml")
    assert "bad.toml" in str(info.value)
    return info.value


@pytest.mark.parametrize("machine", TYPES)
def test_traces_of_every_machine_read_back_to_its_chain_eccentricities(machine, tmp_path):
    """Each run's ΔL over its arc as the chain simulates it (deviations and nuisance terms up to 100″ / 100 µm), with
    an offset r0 and written as a trace CSV (CW in order, CCW reversed), read back through ``trace_csv`` to the chain's
    eccentricities of that run: the reader fits each sample at its angle column, where the commands put the bar.
    dL is written with repr (exact): the tolerance is the fit's rounding, 1e-9 µm."""
    c = load_campaign(demo_campaign(machine))
    fm = ChainBallbarModel(c)
    rng = np.random.default_rng(11)
    scale = np.array([100 * ARCSEC if p.kind == "angle" else 0.1 for p in fm.space.parameters])
    theta = rng.uniform(-1.0, 1.0, len(scale)) * scale
    pred = fm.predict(theta)
    doc = _demo(machine)
    measured = [r for r in doc["ballbar"]["runs"] if not r.get("planned")]
    assert len(measured) == len(c.ballbar.runs) > 0
    for i, ((_, dL), run, table) in enumerate(zip(fm.traces(theta[None]), c.ballbar.runs, measured)):
        angles = c.ballbar.arc_of(run)
        rows = ["angle_deg,dL_um,direction"]
        for direction, order in (("CW", slice(None)), ("CCW", slice(None, None, -1))):
            rows += [f"{float(a)!r},{float(v) * 1e3 + 12.5!r},{direction}" for a, v in zip(angles[order], dL[0][order])]
        (tmp_path / f"run{i}.csv").write_text("\n".join(rows) + "\n", encoding="utf-8")
        for key in [k for k in table if k.endswith("_um")]:
            del table[key]
        table["trace_csv"] = f"run{i}.csv"
    back = _loads(doc, tmp_path)
    index = {(k.run, k.component): j for j, k in enumerate(fm.observations.keys)}
    for i, run in enumerate(back.ballbar.runs):
        assert run.trace_csv == [f"run{i}.csv"]
        assert list(run.repeats) == list(components(c.machine.description, run.pattern))
        for comp, v in run.repeats.items():
            assert v == pytest.approx([pred[index[(i, comp)]]], abs=1e-12), (run.label, comp)
    save_campaign(back, tmp_path / "saved.toml")  # saved with its traces, relative to the saved file
    again = load_campaign(tmp_path / "saved.toml")
    assert [r.trace_csv for r in again.ballbar.runs] == [r.trace_csv for r in back.ballbar.runs]


def _reversed_reading(c, run) -> str:
    """The convention that reads ``run`` with both of its directions turned (the bar on the other side)."""
    a, b = components(c.machine.description, run.pattern)
    k = run.pattern[0]
    return f"{k}0=-{a[1].upper()},{k}90=-{b[1].upper()}"


@pytest.mark.parametrize("machine", TYPES)
def test_a_reading_chosen_over_another_is_read_on_every_machine(machine, tmp_path):
    """``alternative_convention`` and ``alternative_reason`` on a demo campaign: read, checked (an alternative that
    reads the run as its reading does is refused by its key; a reason without a choice too), saved back, and the
    alternative reading is the campaign with that run read in its alternative (other machine-frame offsets)."""
    c = load_campaign(demo_campaign(machine))
    doc = _demo(machine)
    first = doc["ballbar"]["runs"][0]
    other = _reversed_reading(c, c.ballbar.runs[0])
    first["alternative_convention"] = other
    doc["ballbar"]["alternative_reason"] = "the bar's side was not written down"
    chosen = _loads(doc, tmp_path)
    assert [r.label for r in chosen.ballbar.reading_choices()] == [c.ballbar.runs[0].label]
    assert chosen.ballbar.alternative_reason == "the bar's side was not written down"
    alt = chosen.alternative_reading()
    from mtmcal_bayes.conventions import machine_repeats

    run, turned = chosen.ballbar.runs[0], alt.ballbar.runs[0]
    assert (turned.convention, turned.alternative_convention) == (other, None)
    assert turned.repeats is run.repeats or all(np.array_equal(turned.repeats[k], v) for k, v in run.repeats.items())
    mine, theirs = machine_repeats(run, chosen.ballbar), machine_repeats(turned, alt.ballbar)
    assert not np.allclose(np.vstack(list(mine.values())), np.vstack(list(theirs.values())))
    save_campaign(chosen, tmp_path / "saved.toml")
    again = load_campaign(tmp_path / "saved.toml")
    assert again.ballbar.runs[0].alternative_convention == other
    assert again.ballbar.alternative_reason == chosen.ballbar.alternative_reason

    first["alternative_convention"] = "thesis"  # the run's own reading
    assert _error(doc, tmp_path).key == "ballbar.runs[0].alternative_convention"
    del first["alternative_convention"]
    err = _error(doc, tmp_path)
    assert err.key == "ballbar.alternative_reason" and "no run names an alternative_convention" in str(err)


@pytest.mark.parametrize("machine", TYPES)
def test_a_planned_run_with_a_bar_of_its_own(machine, tmp_path, run_cli):
    """A planned run's ``length_mm`` on a demo campaign: kept (not when it is the campaign's), saved back, its
    program written at that bar, and ``simulate`` refuses it by its key (the models take one bar length)."""
    c = load_campaign(demo_campaign(machine))
    doc = _demo(machine)
    run0 = doc["ballbar"]["runs"][0]
    bar = c.ballbar.length + 50.0
    planned = {k: run0[k] for k in ("pattern", "setup", "mount")}
    planned["hold_deg"] = {a.letter: 1.0 for a in c.machine.description.rotary_axes if a.letter != run0["pattern"][0]}
    planned.update(planned=True, repeats=2, length_mm=bar)
    doc["ballbar"]["runs"] = [r for r in doc["ballbar"]["runs"] if not r.get("planned")] + [planned]
    designed = _loads(doc, tmp_path)
    (p,) = designed.ballbar.planned
    assert p.length == bar and f"bar {bar:g} mm" in p.describe()
    save_campaign(designed, tmp_path / "saved.toml")
    assert load_campaign(tmp_path / "saved.toml").ballbar.planned[0].length == bar
    n = len(designed.ballbar.runs) + 1
    code, _, err = run_cli("ncgen", "--run", str(n), str(tmp_path / "saved.toml"), "-o", str(tmp_path / "p.nc"))
    assert code == 0, err
    assert f"bar {bar:g} mm;" in (tmp_path / "p.nc").read_text(encoding="utf-8")
    with pytest.raises(InputError) as info:
        planned_as_runs(designed)
    assert info.value.key == "ballbar.runs" and f"{bar:g} mm" in str(info.value)
    planned["length_mm"] = c.ballbar.length  # the campaign's own: not kept
    assert _loads(doc, tmp_path).ballbar.planned[0].length is None


@pytest.mark.parametrize("machine", TYPES)
def test_the_engine_keys_hold_alike_on_every_machine(machine, tmp_path):
    """The checks the thesis' reader had are the engine's: an offset beyond the bar, a component the pattern has not,
    two set-ups of one tool length, a duplicate run, each refused by its key; and what it allowed is allowed: one
    component alone, or components with repeats of their own where the reading keeps them apart."""
    c = load_campaign(demo_campaign(machine))
    run = c.ballbar.runs[0]
    a, _ = components(c.machine.description, run.pattern)
    missing = next(x for x in ("ex", "ey", "ez") if x not in components(c.machine.description, run.pattern))
    cases = []
    doc = _demo(machine)
    doc["ballbar"]["runs"][0][f"{a}_um"] = [c.ballbar.length * 1e3 + 1.0]
    doc["ballbar"]["runs"][0].pop(f"{components(c.machine.description, run.pattern)[1]}_um")
    cases.append((doc, f"ballbar.runs[0].{a}_um[0]", "not below the bar length"))
    doc = _demo(machine)
    doc["ballbar"]["runs"][0][f"{missing}_um"] = [1.0]
    cases.append((doc, f"ballbar.runs[0].{missing}_um", f"has no component {missing}"))
    doc = _demo(machine)
    first, *_ = doc["ballbar"]["setups"]
    doc["ballbar"]["setups"]["again"] = dict(doc["ballbar"]["setups"][first])
    cases.append((doc, "ballbar.setups.again.R_B_mm", "carries no information"))
    doc = _demo(machine)
    doc["ballbar"]["runs"].insert(1, dict(doc["ballbar"]["runs"][0]))
    cases.append((doc, "ballbar.runs[1]", "repeats ballbar.runs[0]"))
    for doc, key, fragment in cases:
        err = _error(doc, tmp_path)
        assert err.key == key and fragment in str(err), (key, str(err))
    one = _demo(machine)  # one component alone is a run's data, as on the thesis machine
    one["ballbar"]["runs"][0].pop(f"{components(c.machine.description, run.pattern)[1]}_um")
    assert list(_loads(one, tmp_path).ballbar.runs[0].repeats) == [a]
    uneven = _demo(machine)  # so are components with repeats of their own, each its own observation ...
    b = components(c.machine.description, run.pattern)[1]
    uneven["ballbar"]["runs"][0][f"{b}_um"] = [*uneven["ballbar"]["runs"][0][f"{b}_um"], 0.5]
    read = _loads(uneven, tmp_path)
    obs = Observations.from_campaign(read)
    n = {k.component: count for k, count in zip(obs.keys, obs.n) if k.run == 0}
    assert n[b] == n[a] + 1 == len(read.ballbar.runs[0].repeats[b])
    # ... unless the run's reading mixes them: then one of each per repeat
    uneven["ballbar"]["runs"][0]["convention"] = _mixing(read, read.ballbar.runs[0])
    err = _error(uneven, tmp_path)
    assert err.key == "ballbar.runs[0].convention" and "give both components of every repeat" in str(err)


def _mixing(c, run) -> str:
    """A geometry string that reads ``run`` with its two components mixed (a non-diagonal reading matrix)."""
    a, b = (x[1].upper() for x in components(c.machine.description, run.pattern))
    k = run.pattern[0]
    for first, second in ((a, b), (b, a)):
        for s1 in "+-":
            for s2 in "+-":
                g = f"{k}0={s1}{first},{k}90={s2}{second}"
                M = run_matrix(dataclasses.replace(run, convention=g), c.ballbar)
                if not np.allclose(M, np.diag(np.diag(M))):
                    return g
    raise AssertionError(f"no geometry string mixes the components of {run.label}")


def test_the_thesis_keys_are_its_plugins_alone(thesis, tmp_path):
    """The thesis' set-up, mount and ``[ballbar]`` keys are unknown keys on a described machine, the generic run
    geometry and mount position unknown keys in the thesis' format (its patterns fix them); each named by its key.
    Its mounts place the W ball where Tables 2.2/2.3 do (``translation.w_ball``)."""
    from mtmcal_bayes.plugins.thesis.translation import w_ball

    for run in [*thesis.ballbar.runs, *thesis.ballbar.planned]:
        np.testing.assert_array_equal(thesis.ballbar.mounts[run.mount].centre(), w_ball(thesis.ballbar.mounts[run.mount],
                                                                                       run.pattern))
    doc = _demo("trunnion")
    mount = next(iter(doc["ballbar"]["mounts"]))
    doc["ballbar"]["mounts"][mount]["Z_C_mm"] = 30.0
    assert _error(doc, tmp_path).key == f"ballbar.mounts.{mount}.Z_C_mm"
    doc = _demo("trunnion")
    doc["ballbar"]["cr_geometry"] = "RC+LB"
    assert _error(doc, tmp_path).key == "ballbar.cr_geometry"
    for key, value in (("arc_deg", [0.0, 90.0]), ("hold_deg", {"C": 0.0}), ("reversed", True)):
        doc = _thesis_doc()
        doc["ballbar"]["runs"][0][key] = value
        assert _error(doc, tmp_path).key == f"ballbar.runs[0].{key}"
    doc = _thesis_doc()
    mount = next(iter(doc["ballbar"]["mounts"]))
    doc["ballbar"]["mounts"][mount]["position_mm"] = [0.0, 0.0, 60.0]
    assert _error(doc, tmp_path).key == f"ballbar.mounts.{mount}.position_mm"
    assert parse_campaign(dumps(_thesis_doc())).ballbar.runs[0].label == thesis.ballbar.runs[0].label


def _thesis_doc() -> dict:
    from mtmcal_bayes.datasets import builtin_campaign_text

    return tomllib.loads(builtin_campaign_text()[0])
