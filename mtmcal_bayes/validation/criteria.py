"""What simulation-based calibration ranks and when a quantity passes."""

from __future__ import annotations

from ..parameters import IDENTIFIABLE

#: ranked quantities: the eight of Table 4.5, then the other sampled deviations and sigma_model
SBC_QUANTITIES: tuple[str, ...] = IDENTIFIABLE + ("dx_CZ", "dx_BT", "dz_BT", "sigma_model")
#: probabilities of the highest-density intervals whose coverage is counted
INTERVALS: tuple[float, ...] = (0.5, 0.9, 0.95)
#: a quantity fails when its uniformity p-value is below this
P_MIN = 0.01
