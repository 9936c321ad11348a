"""The thesis' names of its machine's deviations, as aliases of their ISO 230-7 symbols (SPEC §19, Table 2.1)."""

from __future__ import annotations

from ...parameters import IDENTIFIABLE

#: the thesis names of the thesis machine's deviations, by ISO symbol (dz_BT: the spindle's offset along Z)
THESIS_NAMES: dict[str, str] = {
    "E_X0C": "dx_CZ", "E_Y0C": "dy_CZ", "E_A0C": "alpha_CZ", "E_B0C": "beta_CZ",
    "E_A0B": "alpha_XB", "E_B0B": "beta_XB", "E_C0B": "gamma_XB",
    "E_X(0C1)B": "dx_BT", "E_A(0C1)B": "alpha_BT", "E_Z(0C1)B": "dz_BT",
    "E_C0X": "gamma_XY", "E_B0X": "beta_YZ", "E_A0Y": "alpha_YZ",
}

#: the quantities a posterior summary of the thesis machine reports: the eight of Table 4.5 in its order, and dx_CZ,
#: dx_BT and dz_BT apart
REPORTED: tuple[str, ...] = IDENTIFIABLE + ("dx_CZ", "dx_BT", "dz_BT")
