"""Machine descriptions (SPEC §19): the rules of a bad description, each one line naming the file and the key,
and the built-in types with the deviations generated from them."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from mtmcal_bayes.datasets import data_path
from mtmcal_bayes.errors import InputError
from mtmcal_bayes.io.machine_reader import (
    BUILTIN_TYPES,
    builtin_description,
    parse_description,
    referenced_description,
)
from mtmcal_bayes.machines import generated, redundant, selected
from mtmcal_bayes.machines.chain import Chain
from mtmcal_bayes.plugins.thesis.names import THESIS_NAMES

#: a valid turn-mill in a campaign's [machine] table; each bad case below changes one thing of it
TURN_MILL = """
[machine]
configuration = "{configuration}"
{extra}
[machine.axes.C]
direction = {c_direction}
point_mm = [0.0, 0.0, 0.0]
[machine.axes.B]
direction = {b_direction}
point_mm = {b_point}
{b_extra}
[machine.spindle]
direction = {spindle_direction}
point_mm = {spindle_point}
"""
DEFAULTS = dict(configuration="w-C'bZYXB(C1)-t", extra="", c_direction='"+Z"', b_direction='"+Y"',
                b_point="[0.0, 0.0, 0.0]", b_extra="", spindle_direction='"-Z"', spindle_point="[0.0, 0.0, 0.0]")


def machine_table(**changes) -> dict:
    """The [machine] table of the turn-mill above with ``changes``."""
    return tomllib.loads(TURN_MILL.format(**(DEFAULTS | changes)))["machine"]


def parse(t: dict, **kw):
    return parse_description(t, "m.toml", "machine", **kw)


def builtin_toml(name: str) -> str:
    return data_path(f"machines/{name}.toml").read_text(encoding="utf-8")


# (id, [machine] table, the key named, a fragment of the message)
BAD = [
    # the configuration
    ("unknown axis letter", machine_table(configuration="w-C'bZYXU(C1)-t"), "configuration", "unknown axis letter 'U'"),
    ("unknown spindle", machine_table(configuration="w-C'bZYXB(C2)-t"), "configuration", "unknown spindle '(C2)'"),
    ("no w-", machine_table(configuration="C'bZYXB(C1)-t"), "configuration", "does not parse"),
    ("no -t", machine_table(configuration="w-C'bZYXB(C1)"), "configuration", "does not parse"),
    ("no bed", machine_table(configuration="w-C'ZYXB(C1)-t"), "configuration", "the bed 'b' must appear once"),
    ("bed twice", machine_table(configuration="w-C'bZYbXB(C1)-t"), "configuration", "the bed 'b' must appear once"),
    ("axis twice", machine_table(configuration="w-C'bZYXBX(C1)-t"), "configuration", "axis X appears twice"),
    ("primed on the tool side", machine_table(configuration="w-C'bZYX'B(C1)-t"), "configuration",
     "X' is primed (moves the workpiece) but stands on the tool side"),
    ("unprimed on the work side", machine_table(configuration="w-CbZYXB(C1)-t"), "configuration",
     "C stands on the workpiece side of the bed 'b' but is not primed"),
    ("missing a linear axis", machine_table(configuration="w-C'bZYB(C1)-t"), "configuration", "no X axis"),
    ("no rotary axis", machine_table(configuration="w-bZYX(C1)-t"), "configuration", "no rotary axis"),
    ("no spindle", machine_table(configuration="w-C'bZYXB-t"), "configuration", "no spindle"),
    ("spindle not last", machine_table(configuration="w-C'bZY(C1)XB-t"), "configuration",
     "the spindle (C1) must be last"),
    ("linear carried by rotary, work side", machine_table(configuration="w-X'C'bZYB(C1)-t"), "configuration",
     "linear axis X is carried by rotary axis C"),
    ("linear carried by rotary, tool side", machine_table(configuration="w-C'bZYBX(C1)-t"), "configuration",
     "linear axis X is carried by rotary axis B"),
    ("configuration missing", {"spindle": {"direction": "-Z"}}, "configuration", "missing"),
    # rotary axes and spindle
    ("rotary axis without direction",
     machine_table() | {"axes": {"C": {"direction": "+Z"}, "B": {"point_mm": [0, 0, 0]}}}, "axes.B.direction", "missing: rotary axis B needs its direction"),
    ("rotary axis not described", machine_table() | {"axes": {"C": {"direction": "+Z"}}},
     "axes.B.direction", "missing: rotary axis B needs its direction"),
    ("direction not a direction", machine_table(b_direction='"+W"'), "axes.B.direction", "is not a direction"),
    ("zero direction", machine_table(b_direction="[0, 0, 0]"), "axes.B.direction", "a zero vector has no direction"),
    ("non-unit direction", machine_table(b_direction="[0, 2, 0]"), "axes.B.direction",
     "[0, 2, 0] is not a unit vector (its length is 2)"),
    ("direction 1e-3 short of unit", machine_table(b_direction="[0, 0.6, 0.799]"), "axes.B.direction",
     "[0, 0.6, 0.799] is not a unit vector (its length is 0.999200"),
    ("spindle without direction", machine_table() | {"spindle": {"point_mm": [0, 0, 0]}},
     "spindle.direction", "missing: the tool's direction"),
    ("spindle direction zero", machine_table(spindle_direction="[0, 0, 0]"),
     "spindle.direction", "a zero vector has no direction"),
    ("bad point", machine_table(b_point="[0, 0]"), "axes.B.point_mm", "expected three numbers"),
    ("travel min > max", machine_table(b_extra="travel_deg = [120, -120]"), "axes.B.travel_deg",
     "expected [min, max] with min < max, got [120, -120]"),
    # two rotary axes of one side on one line: B' described along +Z through C's point on the workpiece side
    ("two rotary axes on one line", machine_table(configuration="w-C'B'bZYX(C1)-t", b_direction='"+Z"',
                                                  b_point="[0.0, 0.0, 250.0]"),
     "axes.C", "axes B and C turn about one line"),
    # the tool along the swivel axis B, through B's point: turning B does not move the tool point
    ("spindle on the line of the axis carrying it", machine_table(spindle_direction='"+Y"',
                                                                  spindle_point="[0.0, 80.0, 0.0]"),
     "spindle.direction", "the spindle lies along the B axis that carries it, on its line"),
    # keys
    ("unknown key", machine_table(extra='tool_length_mm = 100'), "tool_length_mm", "unknown key"),
    ("unknown key of a rotary axis", machine_table(b_extra="travel_mm = [-10, 10]"), "axes.B.travel_mm",
     "unknown key"),
    ("unknown key of the spindle", machine_table() | {"spindle": {"direction": "-Z", "length_mm": 100}},
     "spindle.length_mm", "unknown key"),
    ("axis not in the configuration", machine_table(b_extra="[machine.axes.Q]\ntravel_mm = [0, 1]"), "axes.Q",
     "no axis Q in the configuration"),
    ("rotary axis not in the configuration", machine_table(b_extra='[machine.axes.A]\ndirection = "+X"'), "axes.A",
     "no axis A in the configuration"),
    # the deviations chosen
    ("unknown deviation", machine_table(extra='deviations = ["E_X0C", "E_Q0B"]'), "deviations",
     "'E_Q0B' is not a deviation of this machine"),
    ("thesis name on a described machine", machine_table(extra='deviations = ["dx_CZ"]'), "deviations",
     "'dx_CZ' is not a deviation of this machine"),
    ("no deviations", machine_table(extra="deviations = []"), "deviations", "expected a non-empty list"),
    ("deviation twice", machine_table(extra='deviations = ["E_X0C", "E_X0C"]'), "deviations",
     "E_X0C named twice"),
    # the squareness form
    ("unknown squareness", machine_table(extra='squareness = "tilted"'), "squareness",
     "unknown squareness form 'tilted'"),
    ("rigid squareness, X on the work side", machine_table(configuration="w-C'X'bZYB(C1)-t",
                                                           extra='squareness = "rigid"'),
     "squareness", "the rigid form needs the three linear axes next to the bed on the tool side"),
]


@pytest.mark.parametrize("t, key, fragment", [case[1:] for case in BAD], ids=[case[0] for case in BAD])
def test_a_bad_description_is_one_line_naming_the_file_and_the_key(t, key, fragment):
    with pytest.raises(InputError) as info:
        parse(t)
    err = info.value
    assert err.source == "m.toml"
    assert err.key == f"machine.{key}"
    assert fragment in err.message
    assert str(err).startswith(f"m.toml: machine.{key}: ")
    assert "\n" not in str(err)
    assert "np.float64" not in str(err)


def test_a_deviation_named_by_its_thesis_name_and_its_symbol_is_named_twice():
    t = tomllib.loads(builtin_toml("integrex-i200"))
    t["deviations"] = ["dx_CZ", "E_X0C"]
    with pytest.raises(InputError, match=r"machine\.deviations: dx_CZ named twice"):
        parse(t, builtin="integrex-i200")


def test_the_turn_mill_the_bad_cases_start_from_is_valid():
    desc = parse(machine_table())
    assert [a.letter for a in desc.work_chain] == ["C"]
    assert [a.letter for a in desc.tool_chain] == ["Z", "Y", "X", "B"]
    assert desc.spindle.carrier == "B"
    # the same two axes as in the coaxial case, on different lines, are allowed
    desc = parse(machine_table(configuration="w-C'B'bZYX(C1)-t", b_direction='"+Z"', b_point="[100.0, 0.0, 0.0]"))
    assert [a.letter for a in desc.work_chain] == ["B", "C"]  # from the bed outwards
    # a spindle along the axis carrying it but off its line is moved by it
    parse(machine_table(spindle_direction='"+Y"', spindle_point="[0.0, 0.0, 80.0]"))


def test_a_spindle_on_the_bed_every_axis_moving_the_workpiece():
    t = {"configuration": "w-C'Z'Y'X'b(C1)-t", "axes": {"C": {"direction": "+Z"}}, "spindle": {"direction": "-Z"}}
    desc = parse(t)
    assert desc.tool_chain == () and desc.spindle.carrier == "b"
    assert [d.symbol for d in generated(desc)] == ["E_X0C", "E_Y0C", "E_A0C", "E_B0C", "E_C0C",
                                                   "E_C0X", "E_B0X", "E_A0Y"]
    q = {"X": np.array([1.0]), "Y": np.array([2.0]), "Z": np.array([3.0]), "C": np.array([0.0])}
    tip = Chain(desc, generated(desc)).tool_point(np.zeros((1, 1, 3)), q, {})
    assert np.allclose(tip, 0.0)  # the tool does not move; the workpiece does (-1, -2, -3)
    w = Chain(desc, generated(desc)).work_point(np.zeros((1, 1, 3)), q, {})
    assert np.allclose(w, [[[-1.0, -2.0, -3.0]]])


@pytest.mark.parametrize("name", list(BUILTIN_TYPES))
def test_each_builtin_parses(name):
    desc = builtin_description(name)
    assert desc.builtin == name
    assert ("thesis" in desc.plugins) == (name == "integrex-i200")
    assert desc.spindle.carrier == desc.tool_chain[-1].letter
    assert {d.name for d in selected(desc)} <= {d.name for d in generated(desc)}


# the ISO symbols generated for each built-in type, and those the computed rule of SPEC §21 leaves out of the default
# set (tests/test_default_selection.py checks each with the combination it acts through).  Changed from §19's
# hand-written list (the spindle's errors along its carrier and the squareness) where the rule differs: the spindle's
# offset along itself is the tool's own length error; a position error that only translates the tool side against a
# workpiece side that does not turn with it is a W ball's or sphere's placement, the outermost table's zero likewise;
# an error that turns about a line parallel to one before it acts only with it (head-head E_C0A, E_A(0C1)A); and the
# spindle's position along its carrier acts only with an axis' position before it (E_Y(0C1)B as −E_Y0C), while
# head-head's E_X(0C1)A, no longer "the tool ball's own offset" (the T ball is centred), is kept.
SQUARENESS = ["E_C0X", "E_B0X", "E_A0Y"]
GENERATED = {
    "integrex-i200": (["E_X0C", "E_Y0C", "E_A0C", "E_B0C", "E_C0C", "E_X0B", "E_Z0B", "E_A0B", "E_C0B", "E_B0B",
                       "E_X(0C1)B", "E_Y(0C1)B", "E_A(0C1)B", "E_B(0C1)B", "E_Z(0C1)B", "E_C0X", "E_B0X", "E_A0Y"],
                      ["E_C0C", "E_X0B", "E_Z0B", "E_Y(0C1)B", "E_B(0C1)B", "E_Z(0C1)B"] + SQUARENESS),
    "vertical-turn-mill": (["E_X0C", "E_Y0C", "E_A0C", "E_B0C", "E_C0C", "E_X0B", "E_Z0B", "E_A0B", "E_C0B", "E_B0B",
                            "E_Y(0C1)B", "E_Z(0C1)B", "E_B(0C1)B", "E_C(0C1)B", "E_X(0C1)B",
                            "E_C0X", "E_B0X", "E_A0Y"],
                           ["E_C0C", "E_X0B", "E_Z0B", "E_Y(0C1)B", "E_B(0C1)B", "E_X(0C1)B"] + SQUARENESS),
    "trunnion": (["E_Y0A", "E_Z0A", "E_B0A", "E_C0A", "E_A0A", "E_X0C", "E_Y0C", "E_A0C", "E_B0C", "E_C0C",
                  "E_C0X", "E_B0X", "E_A0Y"],
                 ["E_Z0A", "E_A0C", "E_C0C"] + SQUARENESS),
    "head-head": (["E_X0C", "E_Y0C", "E_A0C", "E_B0C", "E_C0C", "E_Y0A", "E_Z0A", "E_B0A", "E_C0A", "E_A0A",
                   "E_X(0C1)A", "E_Y(0C1)A", "E_A(0C1)A", "E_B(0C1)A", "E_Z(0C1)A", "E_C0X", "E_B0X", "E_A0Y"],
                  ["E_X0C", "E_Y0C", "E_Z0A", "E_C0A", "E_A(0C1)A", "E_Z(0C1)A"] + SQUARENESS),
    # the 45° B head: its positions act only with the C line's (E_U0B as −E_X0C, E_V0B as −0.7071·E_Y0C and the
    # sphere's placement), the spindle's position along Y with E_Y0C, its tilt about Y with B's zero
    "nutating-head": (["E_X0C", "E_Y0C", "E_A0C", "E_B0C", "E_C0C", "E_U0B", "E_V0B", "E_RU0B", "E_RV0B", "E_B0B",
                       "E_X(0C1)B", "E_Y(0C1)B", "E_A(0C1)B", "E_B(0C1)B", "E_Z(0C1)B", "E_C0X", "E_B0X", "E_A0Y"],
                      ["E_C0C", "E_U0B", "E_V0B", "E_Y(0C1)B", "E_B(0C1)B", "E_Z(0C1)B"] + SQUARENESS),
}


@pytest.mark.parametrize("name", list(BUILTIN_TYPES))
def test_the_deviations_generated_for_each_builtin(name):
    desc = builtin_description(name)
    every, left_out = GENERATED[name]
    gen = generated(desc)
    assert [d.symbol for d in gen] == every
    by_symbol = {d.symbol: d.name for d in gen}
    assert sorted(redundant(desc)) == sorted(by_symbol[s] for s in left_out)
    if name != "integrex-i200":  # the default set: the generated less those the rule leaves out
        assert [d.symbol for d in selected(desc)] == [s for s in every if s not in left_out]
        assert all(d.name == d.symbol for d in gen)


def test_the_thesis_machine_keeps_the_thesis_names():
    desc = builtin_description("integrex-i200")
    names = {d.symbol: d.name for d in generated(desc)}
    expected = {"E_X0C": "dx_CZ", "E_Y0C": "dy_CZ", "E_A0C": "alpha_CZ", "E_B0C": "beta_CZ",
                "E_A0B": "alpha_XB", "E_B0B": "beta_XB", "E_C0B": "gamma_XB",
                "E_X(0C1)B": "dx_BT", "E_A(0C1)B": "alpha_BT", "E_Z(0C1)B": "dz_BT",
                "E_C0X": "gamma_XY", "E_B0X": "beta_YZ", "E_A0Y": "alpha_YZ"}
    assert expected == THESIS_NAMES
    assert all(names[s] == n for s, n in expected.items())
    # the thesis has no C zero error and no B position error: those keep their ISO symbols and are not selected
    assert {s for s, n in names.items() if n == s} == {"E_C0C", "E_X0B", "E_Z0B", "E_Y(0C1)B", "E_B(0C1)B"}
    assert desc.deviations == ("dx_BT", "dz_BT", "alpha_BT", "alpha_XB", "beta_XB", "gamma_XB", "gamma_XY",
                               "alpha_YZ", "beta_YZ", "dx_CZ", "dy_CZ", "alpha_CZ", "beta_CZ")
    assert {d.name for d in selected(desc)} == set(expected.values())
    assert desc.squareness == "rigid"


def test_a_description_file_referenced_relative_to_the_campaign(tmp_path):
    (tmp_path / "machines").mkdir()
    (tmp_path / "machines" / "mine.toml").write_text(builtin_toml("trunnion"), encoding="utf-8")
    desc = referenced_description("machines/mine.toml", str(tmp_path / "c.toml"), "machine", tmp_path)
    assert desc.configuration == "w-C'A'bYXZ(C1)-t" and desc.builtin == "" and not desc.plugins
    assert [d.symbol for d in generated(desc)] == GENERATED["trunnion"][0]
    # a built-in type by name
    assert referenced_description("head-head", "c.toml", "machine", tmp_path).builtin == "head-head"
    # a problem in the file names that file and its own key (no "machine." prefix)
    bad = builtin_toml("trunnion").replace('direction = "+X"', 'direction = "+W"')
    (tmp_path / "machines" / "bad.toml").write_text(bad, encoding="utf-8")
    with pytest.raises(InputError) as info:
        referenced_description("machines/bad.toml", "c.toml", "machine", tmp_path)
    assert info.value.source == str(tmp_path / "machines" / "bad.toml") and info.value.key == "axes.A.direction"
    # a missing file, an unknown type: named where the campaign names them
    with pytest.raises(InputError, match="file not found"):
        referenced_description("machines/none.toml", "c.toml", "machine", tmp_path)
    with pytest.raises(InputError) as info:
        referenced_description("five-axis", "c.toml", "machine", tmp_path)
    assert str(info.value).startswith("c.toml: machine: unknown machine type 'five-axis'")
    assert "integrex-i200" in str(info.value)


@pytest.mark.parametrize("case", [c for c in BAD if "configuration" in c[1] or c[0] == "configuration missing"],
                         ids=lambda c: c[0])
def test_every_rule_through_the_command_line(tmp_path, run_cli, case):
    """Each rule as a user meets it: the description in a campaign's [machine], ``report -o``: one line naming the
    file and the key, exit status 2, nothing written."""
    from mtmcal_bayes.io.tomlio import dumps

    _, table, key, words = case
    doc = tomllib.loads(data_path("machines/trunnion-demo.toml").read_text(encoding="utf-8"))
    doc["machine"] = table
    path = tmp_path / "c.toml"
    path.write_text(dumps(doc), encoding="utf-8")
    out = tmp_path / "rep"
    code, _, err = run_cli("report", str(path), "-o", str(out))
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert f"{path}: machine.{key}" in err and words in err, err
    assert not out.exists()


def _directions(name: str) -> list[tuple[str, str | list]]:
    """``(section, direction)`` of every rotary axis and the spindle of built-in type ``name``: ``("axes.B", "+Y")``
    (an inclined one as its vector)."""
    t = tomllib.loads(builtin_toml(name))
    out = [(f"axes.{k}", v["direction"]) for k, v in t["axes"].items() if "direction" in v]
    return out + [("spindle", t["spindle"]["direction"])]


def _with_direction(name: str, section: str, vector: str) -> str:
    """Built-in type ``name``'s description text with ``section``'s direction written as ``vector``."""
    text = builtin_toml(name)
    head = f"[{section}]"
    start = text.index(head)
    line = text.index("direction =", start)
    end = text.index("\n", line)
    return text[:line] + f"direction = {vector}" + text[end:]


def _frame_vector(direction: str) -> np.ndarray:
    v = np.zeros(3)
    v["XYZ".index(direction[1])] = 1.0 if direction[0] == "+" else -1.0
    return v


@pytest.mark.parametrize("name", list(BUILTIN_TYPES))
def test_a_direction_vector_within_1e6_of_unit_is_normalised_and_an_inclined_one_is_kept(tmp_path, name):
    """SPEC §21 and issue 42, defect 7, on every direction of every built-in type: a vector within 1e-6 of unit
    length along a frame axis (off-axis parts ≤ 1e-9 after normalising) is that frame axis, its errors named as
    before; a unit vector at 45° is kept, normalised, as an inclined direction (a rotary axis' errors then named by
    its own basis); a zero vector and one 1e-3 off unit length are refused each with its own reason.  Every refusal
    names the file and the key."""
    base = builtin_description(name)
    path = tmp_path / "m.toml"

    def load():  # as builtin_description reads it (the thesis type's names need it), from a file of its own
        return parse_description(tomllib.loads(path.read_text(encoding="utf-8")), str(path), "", builtin=name)

    for section, direction in _directions(name):
        given = not isinstance(direction, str)  # the type's own inclined axis (the nutating head's B)
        v = np.asarray(direction, float) / np.linalg.norm(direction) if given else _frame_vector(direction)
        k = int(np.argmax(np.abs(v)))
        other = np.eye(3)[(k + 1) % 3]
        near = v * (1.0 + 5e-7) + (0.0 if given else 1e-10) * other  # within the tolerances
        cases = {
            "near": ("[" + ", ".join(repr(float(x)) for x in near) + "]", None),
            "45": ("[" + ", ".join(repr(float(x)) for x in (v + other) * 0.70710678) + "]", "inclined"),
            "zero": ("[0.0, 0.0, 0.0]", "a zero vector has no direction"),
            "long": ("[" + ", ".join(repr(float(x)) for x in v * 1.001) + "]", "is not a unit vector (its length is "
                     "1.001)"),
        }
        if given:  # already inclined: 45° from its nearest frame axis is another inclined direction, not the case
            del cases["45"]
        for case, (vector, fragment) in cases.items():
            path.write_text(_with_direction(name, section, vector), encoding="utf-8")
            if fragment is None:
                desc = load()
                axis = desc.spindle if section == "spindle" else desc.axes[section[-1]]
                if given:
                    assert np.max(np.abs(axis.direction - v)) < 1e-15, (section, case)
                else:
                    assert np.array_equal(axis.direction, v), (section, case)
                assert [d.symbol for d in generated(desc)] == [d.symbol for d in generated(base)]
                continue
            if fragment == "inclined":
                if base.deviations is not None:  # its list names errors of the frame-aligned axis: one line says so
                    with pytest.raises(InputError) as info:
                        load()
                    assert info.value.key == "deviations", (section, str(info.value))
                    assert "is not a deviation of this machine" in info.value.message
                    continue
                desc = load()
                axis = desc.spindle if section == "spindle" else desc.axes[section[-1]]
                assert np.max(np.abs(axis.direction - (v + other) / np.sqrt(2.0))) < 1e-15, (section, case)
                if section != "spindle":
                    K = section[-1]
                    assert axis.inclined
                    assert [d.symbol for d in generated(desc) if d.body == K] == \
                        [f"E_U0{K}", f"E_V0{K}", f"E_RU0{K}", f"E_RV0{K}", f"E_{K}0{K}"]
                continue
            with pytest.raises(InputError) as info:
                load()
            err = info.value
            assert err.source == str(path) and err.key == f"{section}.direction", (section, case, str(err))
            assert fragment in err.message and "\n" not in str(err), (section, case, str(err))
