"""``plan --candidates FILE`` on every machine: a machine from its description reads its user's candidates in its
own terms (its patterns, a set-up or a tool length, a mount or the W ball's position, the arc and the held axes)."""

from __future__ import annotations

import json

import pytest

from mtmcal_bayes.io.machine_reader import demo_campaign

TYPES = ("trunnion", "vertical-turn-mill", "head-head")


@pytest.mark.parametrize("machine", TYPES)
def test_a_user_candidate_equal_to_a_catalogue_run_is_valued_as_it(machine, run_cli, demo_plan, tmp_path):
    """The catalogue's first held-axes run written as a user's candidate (its pattern, set-up, mount and held axes):
    the same information gain and the same sd after it for every target, to 1e-9 relative (the same rows)."""
    doc = json.loads(demo_plan(machine))  # plan --machine MACHINE --json (conftest.demo_plan)
    held = next(c for c in doc["candidates"] if c["kind"] == "held axes")
    # "AR @ T1/W1, C held at 90°": pattern, set-up, mount and held positions as the catalogue names them
    where, hold = held["name"].split(", ", 1)
    pattern, place = where.split(" @ ")
    setup, mount = place.split("/")
    holds = dict((part.split(" held at ")[0], float(part.split(" held at ")[1].rstrip("°")))
                 for part in hold.split(", "))
    path = tmp_path / "candidates.toml"
    path.write_text(f'[[candidate]]\npattern = "{pattern}"\nsetup = "{setup}"\nmount = "{mount}"\nname = "mine"\n'
                    "hold_deg = {" + ", ".join(f"{a} = {v}" for a, v in holds.items()) + "}\n", encoding="utf-8")
    code, out, err = run_cli("plan", "--machine", machine, "--candidates", str(path), "--json")
    assert code == 0, err
    mine = next(c for c in json.loads(out)["candidates"] if c["name"] == "mine")
    assert mine["kind"] == "user" and mine["feasible"] == held["feasible"]
    assert mine["eig_bits"] == pytest.approx(held["eig_bits"], rel=1e-9)
    for t, v in held["targets"].items():
        assert mine["targets"][t]["sd_after"] == pytest.approx(v["sd_after"], rel=1e-9), t


@pytest.mark.parametrize("bad, key", [
    ('pattern = "QX"', "candidate[0].pattern"),
    ('pattern = "CR"\nhold_deg = {Q = 10.0}', "candidate[0].hold_deg.Q"),
    ('pattern = "CR"\nposition_mm = [1.0, 2.0]', "candidate[0].position_mm"),
    ('pattern = "CR"\narc_deg = [90.0, 0.0, 5.0]', "candidate[0].arc_deg"),
])
def test_a_bad_user_candidate_is_one_line_naming_its_key(bad, key, run_cli, tmp_path):
    path = tmp_path / "candidates.toml"
    path.write_text(f"[[candidate]]\n{bad}\nsetup = \"T1\"\n" + ("mount = \"W1\"\n" if "position" not in bad else ""),
                    encoding="utf-8")
    code, _, err = run_cli("plan", demo_campaign("trunnion"), "--candidates", str(path))
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert str(path) in err and key in err, err
