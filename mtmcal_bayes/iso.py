"""ISO 230-7 / ISO 230-1 symbols of the thesis quantities (docs/metrology.md derives them).

Every symbol names the same rotation or offset as the thesis quantity, with the same sign: the value is
the position (µm) or the right-hand rotation (″) about the named axis of the actual axis average line
(or direction of motion) from its nominal place in the machine's reference frame.  The thesis writes
its small rotations as ``I + [ε]×`` with ε = (α, β, γ) about X, Y, Z, which is that convention, so no
sign changes; ``tests/test_iso.py`` checks every symbol against the geometry of the kinematic chain.

The spindle (``C1`` in the configuration code ``w-C'bZYXB(C1)-t``) is located relative to the B axis
that carries it; those symbols use the parenthesised form for one axis relative to another,
``E_X(0C1)B``.  ``dz_BT`` (an offset *along* the spindle axis, the pivot length) and the combination
``dx_CZ_minus_dx_BT`` have no ISO 230-7 symbol: :data:`NO_SYMBOL` says why.
"""

from __future__ import annotations

#: thesis name -> ISO symbol (same value, same sign)
ISO_SYMBOL: dict[str, str] = {
    "dx_CZ": "E_X0C",
    "dy_CZ": "E_Y0C",
    "alpha_CZ": "E_A0C",
    "beta_CZ": "E_B0C",
    "alpha_XB": "E_A0B",
    "beta_XB": "E_B0B",
    "gamma_XB": "E_C0B",
    "dx_BT": "E_X(0C1)B",
    "alpha_BT": "E_A(0C1)B",
    "gamma_XY": "E_C0X",
    "beta_YZ": "E_B0X",
    "alpha_YZ": "E_A0Y",
}

#: thesis quantities without an ISO symbol, and why
NO_SYMBOL: dict[str, str] = {
    "dz_BT": "an offset along the spindle axis (the pivot length from the B axis to the spindle's gauge "
             "line), not a location error of an axis line; ISO 230-7 has no symbol for it",
    "dx_CZ_minus_dx_BT": "a combination (E_X0C − E_X(0C1)B): what the ball bar sees of the C axis's X position "
                         "relative to the spindle; ISO 230-7 names only its two terms",
}


def iso_symbol(name: str) -> str | None:
    """ISO symbol of a thesis quantity, or None (see :data:`NO_SYMBOL`); nuisance terms have none."""
    return ISO_SYMBOL.get(name)


def thesis_name(name_or_symbol: str) -> str:
    """The thesis name of a thesis name or an ISO symbol (``"E_A0B"`` -> ``"alpha_XB"``); unknown names unchanged."""
    by_symbol = {s: n for n, s in ISO_SYMBOL.items()}
    return by_symbol.get(name_or_symbol, name_or_symbol)


def label(name: str) -> str:
    """``"alpha_XB (E_A0B)"``, or the name alone where there is no symbol."""
    s = iso_symbol(name)
    return f"{name} ({s})" if s else name
