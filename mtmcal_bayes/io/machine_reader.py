"""Machine descriptions from TOML (SPEC §19): a campaign's ``[machine]``, a description file, a built-in type.

A description names its ``configuration``, its rotary axes (``[axes.<letter>]`` with ``direction``,
``point_mm``, ``travel_deg``), linear travels (``[axes.<letter>] travel_mm``), the ``[spindle]``
(``direction``, ``point_mm``), optionally ``deviations = [...]`` (a subset) and ``squareness``
(``"motion"`` or ``"rigid"``).  Every problem is one line naming the file and the key
(:class:`~mtmcal_bayes.errors.InputError`).  docs/machines.md describes the format with the built-in types
as worked examples.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .. import units
from ..datasets import data_path
from ..errors import InputError, ParameterError
from ..machines.description import (
    LINEAR,
    ROTARY,
    SPINDLE,
    SQUARENESS,
    Axis,
    MachineDescription,
    Spindle,
    check_geometry,
    parse_configuration,
    parse_direction,
    vector3,
)
from ..machines import plugins
from ..machines.deviations import generated
from .textfiles import read_user_text
from .toml_reader import TomlReader, parse_toml

#: the built-in machine types, by name: file in datasets/machines and one line on what it is
BUILTIN_TYPES: dict[str, str] = {
    "integrex-i200": "the thesis machine: turn-mill, swivel head horizontal at B = 0 (tool along −Z), C table",
    "vertical-turn-mill": "turn-mill with the swivel head vertical at B = 0 (tool along −X), C table",
    "trunnion": "five-axis trunnion table: C on A on the bed, the spindle on the linear axes",
    "head-head": "five-axis head-head: a C head carrying an A fork, the table on the linear axes",
    "nutating-head": "five-axis nutating head: a B head inclined 45° (vertical to horizontal spindle), C table",
}
#: the built-in type whose deviations keep the thesis names
THESIS_TYPE = "integrex-i200"
#: keys of a description (a campaign's [machine] adds name, serial, type and the legacy travels)
DESCRIPTION_KEYS = {"name", "configuration", "axes", "spindle", "deviations", "squareness", "plugins"}


def builtin_description(name: str, *, where: tuple[str, str] | None = None) -> MachineDescription:
    """The built-in description ``name`` (one of :data:`BUILTIN_TYPES`); ``where`` = (source, key) of the reference,
    named in the error for an unknown type."""
    if name not in BUILTIN_TYPES:
        source, key = where or ("<machine>", None)
        raise InputError(source, key, f"unknown machine type {name!r} (built-in types: {', '.join(BUILTIN_TYPES)}; "
                         "or a description file ending in .toml)")
    label = f"<built-in machine {name}>"
    text = data_path(f"machines/{name}.toml").read_text(encoding="utf-8")
    return parse_description(parse_toml(text, label), label, "", builtin=name)


def referenced_description(ref: str, source: str, key: str, base_dir: Path | None) -> MachineDescription:
    """The description a campaign names: a built-in type, or a ``.toml`` file relative to the campaign."""
    if not ref.endswith(".toml"):
        return builtin_description(ref, where=(source, key))
    path = Path(ref) if base_dir is None else Path(base_dir) / ref
    text = read_user_text(path, "machine description")
    return parse_description(parse_toml(text, str(path), "a machine description"), str(path), "")


def parse_description(t: dict, source: str, path: str, *, builtin: str = "",
                      extra_keys: frozenset = frozenset()) -> MachineDescription:
    """A description from its TOML table ``t`` (``path``: its key prefix, ``""`` for a file of its own)."""
    r = TomlReader(source)
    key = (lambda k: f"{path}.{k}" if path else k)  # noqa: E731

    def fail(k, message):
        r.fail(k, message)

    r.check_keys(t, DESCRIPTION_KEYS | set(extra_keys), path)
    configuration = r.string(t, "configuration", path, required=True)
    work, tool = parse_configuration(configuration, fail, key("configuration"))
    axes_t = r.table(t, "axes", path, required=False) or {}
    letters = set(work) | set(tool)
    for letter in axes_t:
        if letter not in letters:
            fail(key(f"axes.{letter}"), f"no axis {letter} in the configuration {configuration!r}")

    def axis(letter: str, work_side: bool) -> Axis:
        where = key(f"axes.{letter}")
        a = axes_t.get(letter)
        if a is not None and not isinstance(a, dict):
            fail(where, "expected a table")
        a = a or {}
        if letter in ROTARY:
            r.check_keys(a, {"direction", "point_mm", "travel_deg"}, where)
            if "direction" not in a:
                fail(f"{where}.direction", f"missing: rotary axis {letter} needs its direction at the home pose "
                                           "(\"+Z\" or a unit vector)")
            direction = parse_direction(a["direction"], fail, f"{where}.direction")
            point = vector3(a["point_mm"], fail, f"{where}.point_mm") if "point_mm" in a else np.zeros(3)
            travel = _travel(r, a, where, key="travel_deg", unit="deg")
            return Axis(letter, True, work_side, direction, point, travel)
        r.check_keys(a, {"travel_mm"}, where)
        direction = np.zeros(3)
        direction[LINEAR.index(letter)] = 1.0
        return Axis(letter, False, work_side, direction, np.zeros(3), _travel(r, a, where, key="travel_mm", unit="mm"))

    work_chain = tuple(axis(letter, True) for letter in work)
    tool_chain = tuple(axis(letter, False) for letter in tool if letter != SPINDLE)
    sp = r.table(t, "spindle", path, required=True)
    r.check_keys(sp, {"direction", "point_mm"}, key("spindle"))
    if "direction" not in sp:
        fail(key("spindle.direction"), "missing: the tool's direction at the home pose (spindle nose to tool tip)")
    spindle = Spindle(parse_direction(sp["direction"], fail, key("spindle.direction")),
                      vector3(sp["point_mm"], fail, key("spindle.point_mm")) if "point_mm" in sp else np.zeros(3),
                      tool_chain[-1].letter if tool_chain else "b")
    squareness = r.string(t, "squareness", path, default="motion")
    if squareness not in SQUARENESS:
        fail(key("squareness"), f"unknown squareness form {squareness!r} (expected one of {', '.join(SQUARENESS)})")
    if squareness == "rigid" and sum(not a.rotary for a in tool_chain) != 3:
        fail(key("squareness"), "the rigid form needs the three linear axes next to the bed on the tool side; "
                                f"{configuration!r} has {''.join(a.letter for a in work_chain if not a.rotary)} on "
                                "the workpiece side (use \"motion\")")
    names = _plugins(t, fail, key("plugins"))
    aliases = tuple(pair for name in names for pair in getattr(plugins.load(name), "aliases", ()))
    desc = MachineDescription(r.string(t, "name", path), configuration, tool_chain, work_chain, spindle, None,
                              squareness, builtin, aliases, names)
    check_geometry(desc, fail, path or "machine")
    if "deviations" in t:
        chosen = t["deviations"]
        if not isinstance(chosen, list) or not all(isinstance(x, str) for x in chosen) or not chosen:
            fail(key("deviations"), "expected a non-empty list of deviation names")
        known = {d.name: d for d in generated(desc)} | {d.symbol: d for d in generated(desc)}
        for name in chosen:
            if name not in known:
                fail(key("deviations"), f"{name!r} is not a deviation of this machine (its deviations: "
                                        f"{', '.join(d.name for d in generated(desc))})")
        names = [known[n].name for n in chosen]
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            fail(key("deviations"), f"{', '.join(twice)} named twice (a deviation by its name and by its ISO "
                                    "symbol is one deviation)")
        desc = MachineDescription(desc.name, configuration, tool_chain, work_chain, spindle,
                                  tuple(known[n].name for n in chosen), squareness, builtin, desc.aliases, desc.plugins)
    return desc


def _plugins(t: dict, fail, key: str) -> tuple[str, ...]:
    """The plug-ins a description names (``plugins = ["thesis"]``), each one that loads (SPEC §20)."""
    names = t.get("plugins", [])
    if not isinstance(names, list) or not all(isinstance(x, str) and x for x in names):
        fail(key, "expected a list of plug-in names, e.g. [\"thesis\"]")
    for name in names:
        try:
            plugins.load(name)
        except (ImportError, AttributeError) as err:
            fail(key, f"plug-in {name!r} does not load ({err}); the built-in ones: {', '.join(plugins.BUILTIN)}, or "
                      "the path of a module whose PLUGIN is the plug-in")
    return tuple(names)


def _travel(r: TomlReader, a: dict, where: str, *, key: str, unit: str) -> tuple[float, float] | None:
    if key not in a:
        return None
    v = r.array(a, key, where, (2,))
    if v[0] >= v[1]:
        r.fail(f"{where}.{key}", f"expected [min, max] with min < max, got [{v[0]:g}, {v[1]:g}]")
    return float(units.to_internal(v[0], unit)), float(units.to_internal(v[1], unit))


def description_of(machine) -> MachineDescription:
    """The description of a campaign's machine: its own, or the thesis machine's (``integrex-i200``) for a campaign
    in the thesis format."""
    return machine.description if machine.description is not None else builtin_description(THESIS_TYPE)


def rtest_demo_campaign(name: str) -> str:
    """The R-test demo campaign of a built-in machine type (R-test runs alone, simulated from a stated truth;
    docs/rtest.md, "The R-test demos"), as a path for :func:`~mtmcal_bayes.io.load_campaign`; a type whose demo
    campaign has R-test runs of its own has none (a :class:`~mtmcal_bayes.errors.ParameterError` on ``demo``)."""
    path = data_path(f"machines/{name}-rtest-demo.toml")
    if not path.is_file():
        raise ParameterError("demo", f"{name} has no separate R-test demo: its demo campaign has R-test runs beside the "
                             "ball bar and the probe (its data 'rtest' is the R-test alone)")
    return str(path)


def demo_campaign(name: str):
    """The demo campaign of a built-in machine type, as a path for :func:`~mtmcal_bayes.io.load_campaign` (None: the
    thesis machine's is the built-in thesis campaign)."""
    if name == THESIS_TYPE:
        return None
    return str(data_path(f"machines/{name}-demo.toml"))
