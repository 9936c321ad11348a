"""``[tolerances]``: the limits a quantity must keep, in a campaign or a file of its own (docs/metrology.md).

::

    [tolerances]
    alpha_XB_arcsec = 30                        # ±30″
    E_B0B_arcsec = 30                           # an ISO 230-7 symbol does as well as the thesis name
    dy_CZ_um = {low = -20, high = 50}           # asymmetric
    beta_CZ_arcsec = {high = 20}                # one-sided: at most 20″

Keys carry the quantity's unit (``_arcsec`` for angles, ``_um`` for lengths); every problem is one
:class:`~mtmcal_bayes.errors.InputError` naming the file and the key.
"""

from __future__ import annotations

import os
from pathlib import Path

from .. import units
from ..campaign import Tolerance
from ..iso import ISO_SYMBOL, thesis_name
from ..parameters import QUANTITIES
from .textfiles import read_user_text
from .toml_reader import TomlReader, kind_of, parse_toml


def parse_tolerances(r: TomlReader, table: dict, path: str = "tolerances") -> dict[str, Tolerance]:
    """The tolerances of a parsed ``[tolerances]`` table, by thesis name, internal units."""
    out: dict[str, Tolerance] = {}
    for key, spec in table.items():
        full = f"{path}.{key}"
        given, unit = units.split_unit_key(key)
        name = thesis_name(given)
        if name not in QUANTITIES:
            r.fail(full, f"unknown quantity {given!r} (expected a thesis name such as alpha_XB or an ISO symbol "
                   f"such as {ISO_SYMBOL['alpha_XB']}, with _arcsec or _um)")
        want = QUANTITIES[name].unit
        if unit != want:
            r.fail(full, f"{name} is {'an angle' if want == 'arcsec' else 'a length'}: write {given}_{want}")
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
                              None if high is None else units.to_internal(high, unit), full)
    return out


def load_tolerances(path: str | os.PathLike) -> dict[str, Tolerance]:
    """The ``[tolerances]`` of a TOML file of its own (``--tolerances FILE.toml``)."""
    source = str(path)
    r = TomlReader(source)
    doc = parse_toml(read_user_text(Path(path), "tolerances file"), source, "a [tolerances] table")
    r.check_keys(doc, {"tolerances"}, "")
    table = r.table(doc, "tolerances", "")
    if not table:
        r.fail("tolerances", "no tolerance given")
    return parse_tolerances(r, table)
