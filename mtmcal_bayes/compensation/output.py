"""Text of a compensation: the corrections, the residual error and what X/Y/Z cannot correct."""

from __future__ import annotations

from .. import units
from .options import OFF_TOOL_MM


def format_compensation(result) -> str:
    """What ``compensate`` prints for a :class:`~.result.CompensationResult`."""
    j = result.summary()
    lines = [f"{result.program}: {j['blocks']} motion blocks compensated ({j['method']}, {j['model']}, "
             f"tool point {j['point']}, deviations = {j['values']}) -> {result.output}"]
    c = j["correction_um"]["max_abs"]
    lines.append(f"  largest correction: X {c['X']:.1f} µm, Y {c['Y']:.1f} µm, Z {c['Z']:.1f} µm; "
                 f"tool-point error before {j['error_before_um']['max']:.1f} µm")
    lines.append(f"  residual tool-point error ({j['uncertainty_from']}): mean ≤ {j['residual_um']['mean_max']:.1f} µm, "
                 f"95 % ≤ {j['residual_um']['p95_max']:.1f} µm per block")
    lines.append(f"    the whole program: with 95 % probability no block's error exceeds {j['residual_um']['program_p95']:.1f} µm")
    if any(d["status"] == "left at zero" for d in j.get("not_measured", ())):
        seen = j["residual_determined_um"]
        lines.append(f"    with the deviations left at zero taken as zero: 95 % ≤ {seen['p95_max']:.1f} µm per block, "
                     f"{seen['program_p95']:.1f} µm the whole program (what the data vouch for; the rest is their "
                     "prior spread)")
    lines.append(f"  not compensable by X/Y/Z (tool-axis tilt; error {OFF_TOOL_MM:g} mm along the tool from the "
                 "compensated point):")
    off = f"error_at_{OFF_TOOL_MM:g}mm_off_the_tool_point_um"
    choice = j.get("reading_choice")
    resting = set(choice["rests_on_choice"]) if choice else set()
    for r in j["not_compensable"]:
        name = r["name"] + (f" {choice['mark']}" if r["name"] in resting else "")
        lines.append(f"    {name:14s} {r['tool_tilt_arcsec']:7.2f} ″  {r[off]:6.2f} µm")
    if choice:
        lines += choice_lines(choice)
    if "not_measured" in j:
        lines += not_measured_lines(j["not_measured"])
    return "\n".join(lines)


def not_measured_lines(notes: list[dict]) -> list[str]:
    """The deviations not compensated with a value the data determine one by one, those sharing a reason on one
    line."""
    if not notes:
        return ["  every deviation of the machine is compensated with a value the data determine"]
    by_why: dict[str, list[str]] = {}
    for d in notes:
        by_why.setdefault(d["why"], []).append(d["name"])
    return ["  not compensated with a measured value:"] + [f"    {', '.join(names)}: {why}"
                                                         for why, names in by_why.items()]


def choice_lines(choice: dict) -> list[str]:
    """The summary's lines on the deviations that rest on the campaign's choice of reading (each with its value and,
    marked, its value under the best rejected reading), and what the mark means."""
    if not choice["rests_on_choice"]:
        return ["  no deviation used rests on the campaign's choice of reading (none moves by more than its sd under "
                "the best rejected reading)"]
    shown = []
    for name in choice["rests_on_choice"]:
        d = choice["deviations"][name]
        sym = units.SYMBOL[d["unit"]]
        shown.append(f"{name} {d['value']:.2f} {sym} ({choice['mark']} {d['alternative']:.2f} {sym})")
    return [f"  rests on the campaign's choice of reading ({choice['mark']}): " + ", ".join(shown), f"  {choice['note']}"]
