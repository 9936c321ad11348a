"""``[tolerances]``: the limits a quantity must keep, in a campaign or a file of its own (docs/metrology.md).

::

    [tolerances]
    alpha_XB_arcsec = 30                        # ±30″
    E_B0B_arcsec = 30                           # an ISO 230-7 symbol does as well as the thesis name
    dy_CZ_um = {low = -20, high = 50}           # asymmetric
    beta_CZ_arcsec = {high = 20}                # one-sided: at most 20″

Keys carry the quantity's unit (``_arcsec`` for angles, ``_um`` for lengths) and name it by its ISO 230-7 symbol
or by an alias the machine gives it (the thesis names on the thesis machine).  A quantity is resolved against the
campaign's own machine (:func:`machine_names`): a campaign's ``[tolerances]`` when it is read, a file of its own
(:func:`load_tolerances`, which checks only what the key alone says) when it meets a campaign
(:func:`resolve_tolerances`).  Every problem is one :class:`~mtmcal_bayes.errors.InputError` naming the file and
the key.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

from .. import units
from ..campaign import Tolerance
from ..errors import InputError, ParameterError
from ..machines.deviations import generated
from ..parameters import DERIVED, quantity_unit
from .machine_reader import description_of
from .textfiles import read_user_text
from .toml_reader import TomlReader, kind_of, parse_toml


def machine_names(machine) -> dict[str, str]:
    """Every name a tolerance may give a quantity of ``machine`` (a :class:`~mtmcal_bayes.campaign.Machine`) ->
    the quantity's name in its posterior: each location error of its description by its name and by its ISO 230-7
    symbol (on the thesis machine the name is the thesis' alias), and each derived quantity
    (:data:`~mtmcal_bayes.parameters.DERIVED`) whose terms the machine has."""
    out: dict[str, str] = {}
    for d in generated(description_of(machine)):
        out[d.symbol] = d.name
        out[d.name] = d.name
    have = set(out.values())
    out.update({q: q for q, w in DERIVED.items() if set(w) <= have})
    return out


def _unit_of(given: str) -> str | None:
    """``"arcsec"`` or ``"um"`` of a quantity known by its name alone (a thesis name, an ISO symbol), else None."""
    try:
        return quantity_unit(given)
    except KeyError:
        return None


def parse_tolerances(r: TomlReader, table: dict, path: str = "tolerances", names: dict[str, str] | None = None
                     ) -> dict[str, Tolerance]:
    """The tolerances of a parsed ``[tolerances]`` table in internal units.  ``names``
    (:func:`machine_names` of the campaign's machine): keyed by the machine's own quantity names, a name it does
    not have an error; None (a file of its own): keyed by the name as written, resolved later
    (:func:`resolve_tolerances`)."""
    out: dict[str, Tolerance] = {}
    for key, spec in table.items():
        full = f"{path}.{key}"
        given, unit = units.split_unit_key(key)
        if names is not None:
            if given not in names:
                r.fail(full, _not_here(given, names))
            name = names[given]
        else:
            name = given
        want = _unit_of(name)
        if want is None:
            r.fail(full, f"unknown quantity {given!r} (expected an ISO 230-7 symbol such as E_B0C or a thesis name "
                   "such as alpha_XB, with _arcsec or _um)")
        if unit != want:
            r.fail(full, f"{given} is {'an angle' if want == 'arcsec' else 'a length'}: write {given}_{want}")
        if name in out:
            r.fail(full, f"a second tolerance for {name} (already given as {out[name].key})")
        if isinstance(spec, dict):
            r.check_keys(spec, {"low", "high"}, full)
            if not spec:
                r.fail(full, "an empty table: give low, high or both")
            low = r.number(spec, "low", full, required=False)
            high = r.number(spec, "high", full, required=False)
            if low is not None and high is not None and not low < high:
                r.fail(f"{full}.high", f"must be greater than low ({high:g} ≤ {low:g})")
        elif isinstance(spec, (int, float)) and not isinstance(spec, bool):
            half = r.number(table, key, path, positive=True)
            low, high = -half, half
        else:
            r.fail(full, f"expected a number (± limit) or a table {{low = .., high = ..}}, got {kind_of(spec)}")
        out[name] = Tolerance(name, None if low is None else units.to_internal(low, unit),
                              None if high is None else units.to_internal(high, unit), full, r.source)
    return out


def _not_here(given: str, names: dict[str, str]) -> str:
    """Why ``given`` names no quantity of a machine whose names are ``names``, with the names it has."""
    own = sorted({n for n in names.values()})
    aliases = sorted(a for a, n in names.items() if a != n)
    return (f"{given} is not a quantity of this machine; it has {', '.join(own)}"
            + (f" (also named {', '.join(aliases)})" if aliases else ""))


def resolve_tolerances(tolerances: dict[str, Tolerance] | None, machine, *, strict: bool = True
                       ) -> tuple[dict[str, Tolerance] | None, list[str]]:
    """``({name: Tolerance}, not_here)``: ``tolerances`` keyed by the quantity names of ``machine`` (each given by
    a name or ISO symbol of it, :func:`machine_names`) and the names given that it does not have.  ``strict``: such
    a name is an :class:`~mtmcal_bayes.errors.InputError` naming the tolerance's file and key (a
    :class:`~mtmcal_bayes.errors.ParameterError` of ``tolerances`` for one made in Python); otherwise it is left
    out and listed (a plant-wide set on a machine type that lacks it).  Two names of one quantity are an error
either way.  None stays None."""
    if tolerances is None:
        return None, []
    names = machine_names(machine)
    out: dict[str, Tolerance] = {}
    missing: list[str] = []
    for given, t in tolerances.items():
        name = names.get(t.name)
        if name is None and not strict:
            missing.append(t.name)
            continue
        problem = (_not_here(t.name, names) if name is None else
                   f"a second tolerance for {name} (already given as {out[name].key or out[name].name})"
                   if name in out else None)
        if problem is not None:
            if t.source:
                raise InputError(t.source, t.key or None, problem)
            raise ParameterError("tolerances", problem)
        out[name] = dataclasses.replace(t, name=name)
    return out, missing


def load_tolerances(path: str | os.PathLike) -> dict[str, Tolerance]:
    """The ``[tolerances]`` of a TOML file of its own (``--tolerances FILE.toml``), keyed by the names as written:
    :func:`resolve_tolerances` gives them a campaign's machine."""
    source = str(path)
    r = TomlReader(source)
    doc = parse_toml(read_user_text(Path(path), "tolerances file"), source, "a [tolerances] table")
    r.check_keys(doc, {"tolerances"}, "")
    table = r.table(doc, "tolerances", "")
    if not table:
        r.fail("tolerances", "no tolerance given")
    return parse_tolerances(r, table)
