"""What simulation-based calibration ranks and when a quantity passes."""

from __future__ import annotations

from ..parameters import IDENTIFIABLE

#: ranked quantities: the eight of Table 4.5, then the other sampled deviations and sigma_model (with touch-probe
#: data :func:`sbc_quantities` ranks each instrument's discrepancy scale)
SBC_QUANTITIES: tuple[str, ...] = IDENTIFIABLE + ("dx_CZ", "dx_BT", "dz_BT", "sigma_model")


def sbc_quantities(post) -> tuple[str, ...]:
    """The quantities ranked for a posterior: the deviations of :data:`SBC_QUANTITIES`, then its discrepancy
    scales."""
    return SBC_QUANTITIES[:-1] + tuple(post.scales)
#: probabilities of the highest-density intervals whose coverage is counted
INTERVALS: tuple[float, ...] = (0.5, 0.9, 0.95)
#: a quantity fails when its uniformity p-value is below this
P_MIN = 0.01
