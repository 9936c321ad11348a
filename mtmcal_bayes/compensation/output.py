"""Text of a compensation: the corrections, the residual error and what X/Y/Z cannot correct."""

from __future__ import annotations

from .kinematics import OFF_TOOL_MM


def format_compensation(result) -> str:
    """What ``compensate`` prints for a :class:`~.compensate.CompensationResult`."""
    j = result.summary()
    lines = [f"{result.program}: {j['blocks']} motion blocks compensated ({j['method']}, {j['model']}, "
             f"tool point {j['point']}, deviations = {j['values']}) -> {result.output}"]
    c = j["correction_um"]["max_abs"]
    lines.append(f"  largest correction: X {c['X']:.1f} µm, Y {c['Y']:.1f} µm, Z {c['Z']:.1f} µm; "
                 f"tool-point error before {j['error_before_um']['max']:.1f} µm")
    lines.append(f"  residual tool-point error ({j['uncertainty_from']}): mean ≤ {j['residual_um']['mean_max']:.1f} µm, "
                 f"95 % ≤ {j['residual_um']['p95_max']:.1f} µm per block")
    lines.append(f"  not compensable by X/Y/Z (tool-axis tilt; error {OFF_TOOL_MM:g} mm along the tool from the "
                 "compensated point):")
    off = f"error_at_{OFF_TOOL_MM:g}mm_off_the_tool_point_um"
    for r in j["not_compensable"]:
        lines.append(f"    {r['name']:14s} {r['tool_tilt_arcsec']:7.2f} ″  {r[off]:6.2f} µm")
    return "\n".join(lines)
