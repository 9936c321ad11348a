"""docs/machines.md, "The identified axis lines in a controller's kinematic description": every number `axes` prints
for a built-in type is named in that type's table, and the table of tilts read from a direction has the chain's
signs (each orientation error of a line, turned by +h, is read back as +h)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, builtin_description
from mtmcal_bayes.machines.chain import Chain
from mtmcal_bayes.machines.deviations import generated
from mtmcal_bayes.posterior import axis_lines as al

DOC = Path(__file__).resolve().parents[1] / "docs" / "machines.md"
TITLE = "## The identified axis lines in a controller's kinematic description"


def _section() -> str:
    text = DOC.read_text(encoding="utf-8")
    start = text.index(TITLE)
    end = text.find("\n## ", start + len(TITLE))
    return text[start:end if end >= 0 else None]


def _numbers(desc, dev=None) -> dict:
    """What `axes` prints for a description: (element, quantity) -> value at the given deviations (internal units)."""
    chain = Chain(desc, generated(desc))
    return {k: float(v[0][0]) for k, v in al._quantities(desc, al._lines(chain, desc, dev or {}, 1)).items()}


@pytest.mark.parametrize("machine", sorted(BUILTIN_TYPES))
def test_every_axes_number_is_named_in_its_type_table(machine):
    m = re.search(rf"### On the `{re.escape(machine)}`(.*?)(?=\n### |\Z)", _section(), re.S)
    assert m, f"no table for {machine}"
    missing = [f"{e} {q}" for e, q in _numbers(builtin_description(machine)) if f"`{e} {q}`" not in m.group(1)]
    assert not missing, f"{machine}: not named in docs/machines.md: {missing}"


def _tilt_table() -> dict[str, list]:
    """The docs' table: nominal direction ('+X', '-Z', ...) -> per frame axis X, Y, Z: None or (sign, component)."""
    rows = {}
    for line in _section().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != 5 or not re.match(r"^[+−]\s?[XYZ]\b", cells[0]):
            continue
        label = cells[0][:2].replace("−", "-")
        tilts = []
        for c in cells[2:]:
            m = re.fullmatch(r"(−?)`direction_([xyz])`", c)
            tilts.append(None if m is None else (-1.0 if m.group(1) else 1.0, m.group(2)))
        rows[label] = tilts
    return rows


def test_tilt_table_has_the_chains_signs():
    table = _tilt_table()
    assert set(table) >= {"+X", "+Y", "+Z", "-X", "-Z"}
    h = 1e-5  # rad
    checked = 0
    for machine in BUILTIN_TYPES:
        desc = builtin_description(machine)
        nominal = _numbers(desc)
        for dev in generated(desc):
            if dev.role != "orientation" or dev.component is None:  # an inclined axis' own basis: its section
                continue
            d = np.array([nominal[dev.body, f"direction_{a}"] for a in "xyz"])
            k = int(np.argmax(np.abs(d)))
            label = ("+" if d[k] > 0 else "-") + "XYZ"[k]
            cell = table[label][dev.component]
            if cell is None:  # a turn about the line's own axis: its zero position, no tilt
                assert dev.component == k, (machine, dev.symbol)
                continue
            sign, comp = cell
            moved = _numbers(desc, {dev.name: np.array([h])})
            read = sign * (moved[dev.body, f"direction_{comp}"] - nominal[dev.body, f"direction_{comp}"])
            assert read == pytest.approx(h, rel=1e-6), (machine, dev.symbol)
            checked += 1
    assert checked >= 12
