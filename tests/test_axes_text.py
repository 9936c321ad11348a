"""``axes``' text sets the description's nominal value beside each identified one (issue 42, defect 10), as
docs/machines.md ("How to read axes") compares them, on every built-in type."""

from __future__ import annotations

import json

import numpy as np
import pytest

from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, builtin_description


def _table(text: str) -> list[str]:
    """``axes``' text less the lines that give an inclined element's nominal line and basis (above the table)."""
    return [line for line in text.splitlines() if line.split()[1:2] != ["inclined"]]


def _rows(text: str) -> dict[tuple[str, str], tuple[float, float]]:
    """``(element, quantity) -> (nominal, mean)`` of ``axes``' text."""
    out = {}
    for line in _table(text)[2:]:
        element, quantity, nominal, mean = line.split()[:4]
        out[element, quantity] = (float(nominal), float(mean))
    return out


@pytest.mark.parametrize("machine", list(BUILTIN_TYPES))
def test_axes_text_has_the_descriptions_nominal_beside_the_identified_value(run_cli, machine):
    code, text, err = run_cli("axes", "--machine", machine)
    assert code == 0, err
    assert _table(text)[1].split() == ["nominal", "identified"]
    inclined = sum(a.inclined for a in builtin_description(machine).rotary_axes)
    assert len(_table(text)) == len(text.splitlines()) - inclined
    rows = _rows(text)
    code, out, err = run_cli("axes", "--machine", machine, "--json")
    assert code == 0, err
    lines = json.loads(out)["lines"]
    assert len(rows) == len(lines)
    for r in lines:  # the text's columns are the JSON's numbers
        nominal, mean = rows[r["element"], r["quantity"]]
        assert nominal == pytest.approx(r["nominal"], abs=5e-7) and mean == pytest.approx(r["mean"], abs=5e-7)
    # the nominal of every line is the description's own point and direction (the point of a line along frame
    # axis k: the described point_mm, the perpendicular's foot from it)
    desc = builtin_description(machine)
    elements = {a.letter: (a.point, a.direction) for a in desc.rotary_axes}
    if desc.spindle.carrier != "b":
        elements["C1"] = (desc.spindle.point, desc.spindle.direction)
    checked = 0
    for name, (point, direction) in elements.items():
        for i, a in enumerate("xyz"):
            assert rows[name, f"point_{a}"][0] == pytest.approx(point[i], abs=5e-7)
            assert rows[name, f"direction_{a}"][0] == pytest.approx(direction[i], abs=5e-7)
            checked += 2
    assert checked == 6 * len(elements) >= 12
    for (element, quantity), (nominal, _) in rows.items():
        if quantity == "pivot_distance":  # between nominal lines: along the common normal, or across parallel ones
            (p1, d1), (p2, d2) = (elements[e] for e in element.split("-"))
            n = np.cross(d1, d2)
            gap = p2 - p1
            want = abs(gap @ n) / np.linalg.norm(n) if np.linalg.norm(n) > 1e-12 else np.linalg.norm(np.cross(gap, d1))
            assert nominal == pytest.approx(want, abs=5e-7), element
