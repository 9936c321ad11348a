"""The identified axis lines of a machine (issue 37, item 4): what a controller's kinematic description needs.

For each rotary axis and the spindle: the direction (unit vector) and a point of its actual average line at the
home pose, in the machine frame — the nominal line displaced by the axis' own location errors and by those of
every axis below it in the chain (:class:`~mtmcal_bayes.machines.chain.Chain`, commands all 0); the point is the
foot of the perpendicular from the description's ``point_mm`` (so a point's offset is the line's position error
there, as ISO 230-7 states it).  And the distance between the lines of successive rotary axes of one side (and
between the spindle and the axis carrying it): the pivot distances of a kinematic description.

An inclined rotary axis (SPEC §21) is given with its basis u, v in the machine frame, the directions its location
errors are named by (``E_U0K``, ``E_V0K`` along them, ``E_RU0K``, ``E_RV0K`` about them), beside its nominal line
(direction and point, as a controller's kinematic table takes an oblique axis); so is a spindle whose basis relative
to its carrier leaves the frame axes (``E_U(0C1)K`` ...).

Each number is a function of the deviations; its posterior comes from the draws.  A number the data do not
determine — its first-order change with the deviations has a part along a direction the measurements cannot see
(:meth:`~mtmcal_bayes.inference.identifiability.Identifiability.estimable`) — is marked ``determined = False``:
its interval is the prior's, not a measurement.  A pivot distance whose nominal is 0 (intersecting lines) has no
first order there; it is determined when every component of the gap between the lines is (:func:`_gap_parts`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pandas as pd

from .. import units
from ..arviz_import import az
from ..inference.results import HDI_PROB
from ..iso import iso_symbol
from ..machines.chain import Chain
from ..machines.description import SPINDLE, MachineDescription
from ..machines.deviations import generated, spindle_basis, spindle_own_basis
from ..machines.selection import redundant

#: columns of the table, per row
COLUMNS = ["element", "quantity", "unit", "nominal", "mean", "sd", "hdi_low", "hdi_high", "determined"]


def _lines(chain: Chain, desc: MachineDescription, dev: dict[str, np.ndarray], n: int) -> dict[str, tuple]:
    """Per element (rotary axis letter, ``"C1"``): ``(point (n, 3) mm, direction (n, 3))`` of its actual line."""
    out = {}
    for side in (desc.work_chain, desc.tool_chain):
        for i, ax in enumerate(side):
            if ax.rotary:
                out[ax.letter] = _carried(chain, side[: i + 1], ax.letter, point=ax.point, direction=ax.direction,
                                          dev=dev, n=n)
    if desc.spindle.carrier != "b":
        out[SPINDLE] = _carried(chain, desc.tool_chain, SPINDLE, point=desc.spindle.point,
                                direction=desc.spindle.direction, dev=dev, n=n)
    return out


def _carried(chain: Chain, below, body: str, *, point, direction, dev, n: int):
    """The line through ``point`` along ``direction`` displaced by ``body``'s errors, then by those of the axes
    ``below`` (bed outwards; the body's own axis last of them when it is an axis) at the home pose."""
    v = np.broadcast_to(np.stack([point, point + direction]), (n, 2, 3)).copy()
    v = chain.bodies[body].displace(v, dev)
    for ax in reversed([a for a in below if a.letter != body]):
        v = chain.bodies[ax.letter].displace(v, dev)
    d = v[:, 1] - v[:, 0]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    rel = point - v[:, 0]
    foot = v[:, 0] + np.einsum("ni,ni->n", rel, d)[:, None] * d  # the line's point nearest the nominal point
    return foot, d


def _distance(p1, d1, p2, d2) -> np.ndarray:
    """Distance (n,) between two lines: along their common perpendicular, or between parallel lines."""
    cross = np.cross(d1, d2)
    norm = np.linalg.norm(cross, axis=1)
    gap = p2 - p1
    skew = np.abs(np.einsum("ni,ni->n", gap, cross)) / np.where(norm > 1e-12, norm, 1.0)
    parallel = np.linalg.norm(np.cross(gap, d1), axis=1)
    return np.where(norm > 1e-9, skew, parallel)


def _gap_parts(p1, d1, p2, d2) -> np.ndarray:
    """Smooth components (n, k) of the gap between two lines whose norm is their distance: along the common
    normal (k = 1), or, for parallel lines, the gap's two components across them (k = 2).  The distance is not
    differentiable where it is 0; these are, and say what the data must see of it there."""
    cross = np.cross(d1, d2)
    norm = np.linalg.norm(cross, axis=1)
    gap = p2 - p1
    if np.all(norm > 1e-9):
        return (np.einsum("ni,ni->n", gap, cross) / norm)[:, None]
    e = np.eye(3)[np.argmin(np.abs(d1[0]))]  # a fixed axis across the lines
    u = np.cross(d1, e)
    u /= np.linalg.norm(u, axis=1)[:, None]
    v = np.cross(d1, u)
    return np.stack([np.einsum("ni,ni->n", gap, u), np.einsum("ni,ni->n", gap, v)], axis=1)


def _pairs(desc: MachineDescription, lines: dict) -> list[tuple[str, str]]:
    """The successive rotary axes of each side, and the spindle with its carrier: the pivot distances' lines."""
    pairs = []
    for side in (desc.work_chain, desc.tool_chain):
        rot = [a.letter for a in side if a.rotary]
        pairs += list(zip(rot, rot[1:]))
    if SPINDLE in lines and desc.spindle.carrier in lines:
        pairs.append((desc.spindle.carrier, SPINDLE))
    return pairs


def _quantities(desc: MachineDescription, lines: dict) -> dict[tuple[str, str], tuple[np.ndarray, str]]:
    """Every reported number ``(element, quantity) -> (values (n,), unit)``, internal units (mm, or 1 for a
    direction's components)."""
    out = {}
    for name, (p, d) in lines.items():
        for i, a in enumerate("xyz"):
            out[name, f"point_{a}"] = (p[:, i], "mm")
        for i, a in enumerate("xyz"):
            out[name, f"direction_{a}"] = (d[:, i], "1")
    for a, b in _pairs(desc, lines):
        out[f"{a}-{b}", "pivot_distance"] = (_distance(*lines[a], *lines[b]), "mm")
    return out


def _distance_parts(desc: MachineDescription, lines: dict) -> dict[str, np.ndarray]:
    """:func:`_gap_parts` of every pivot distance, by element (``"B-C1"``), each (n, k)."""
    return {f"{a}-{b}": _gap_parts(*lines[a], *lines[b]) for a, b in _pairs(desc, lines)}


def inclined_bases(desc: MachineDescription) -> dict[str, dict[str, list[float]]]:
    """Per element named in its own basis (an inclined rotary axis; the spindle where its basis relative to its
    carrier is not along frame axes): its nominal line (``direction``, ``point_mm``) and basis (``u``, ``v``), each
    a list of 3 floats in the machine frame at the home pose.  Empty on a machine whose axes lie along frame axes."""
    out = {}
    for ax in desc.rotary_axes:
        if ax.inclined:
            u, v = ax.basis
            out[ax.letter] = {"direction": ax.direction, "point_mm": ax.point, "u": u, "v": v}
    if spindle_own_basis(desc):
        u, v = spindle_basis(desc)
        out[SPINDLE] = {"direction": desc.spindle.direction, "point_mm": desc.spindle.point, "u": u, "v": v}
    return {k: {name: [float(x) + 0.0 for x in vec] for name, vec in b.items()} for k, b in out.items()}


def _shown(v: list[float]) -> str:
    return "[" + ", ".join(f"{x:.9g}" for x in v) + "]"


@dataclass
class AxisLines:
    """The identified axis lines: ``table`` (:data:`COLUMNS`; lengths in mm, direction components unitless),
    ``machine`` its configuration, ``bases`` :func:`inclined_bases` of its description."""

    table: pd.DataFrame
    machine: str
    bases: dict | None = None

    def to_json(self) -> dict:
        rows = self.table.to_dict(orient="records")
        out = {"machine": self.machine, "hdi_prob": HDI_PROB, "lines": rows}
        if self.bases:
            out["inclined"] = self.bases
        return out

    def to_csv(self) -> str:
        return self.table.to_csv(index=False, float_format="%.9g")

    def to_text(self) -> str:
        lines = [f"Identified axis lines of {self.machine} at the home pose (machine frame; point: the line's point "
                 "nearest the described point_mm; nominal: the description's; identified: mean ± sd, 95 % HDI)",
                 f"  {'':6s} {'':15s} {'nominal':>14s} {'identified':>14s}"]
        for element, b in (self.bases or {}).items():
            what = "spindle" if element == SPINDLE else f"{element} axis"
            lines.insert(1, f"  {element:6s} inclined {what}: nominal line along {_shown(b['direction'])} through "
                            f"{_shown(b['point_mm'])} mm; its basis u = {_shown(b['u'])}, v = {_shown(b['v'])} "
                            "(its position errors along u, v, its orientation errors about them)")
        for _, r in self.table.iterrows():
            mark = "" if r["determined"] else "   not determined: the prior's, not a measurement"
            lines.append(f"  {r['element']:6s} {r['quantity']:15s} {r['nominal']:14.6f} {r['mean']:14.6f} ± "
                         f"{r['sd']:.6f} {r['unit']:2s} [{r['hdi_low']:.6f}, {r['hdi_high']:.6f}]{mark}")
        return "\n".join(lines)


def axis_lines(result) -> AxisLines:
    """The axis lines of a posterior (:class:`~mtmcal_bayes.posterior.sample.PosteriorResult` of a campaign on any
    machine, the thesis one included), from its draws."""
    from ..inference.identifiability import campaign_identifiability
    from ..io.machine_reader import description_of

    post = result.log_posterior
    desc = description_of(post.campaign.machine)
    chain = Chain(desc, generated(desc))
    devs = [p for p in post.space.parameters if p.group == "deviation"]
    draws = {p.name: units.to_internal(np.ravel(np.asarray(result.idata.posterior[p.name])), p.unit) for p in devs}
    n = len(next(iter(draws.values())))
    values = _quantities(desc, _lines(chain, desc, draws, n))
    nominal = _quantities(desc, _lines(chain, desc, {}, 1))
    # first-order change of every number per display unit of each deviation: what the data must see of it
    ident = result.identifiability or campaign_identifiability(post)
    grads, part_grads = {}, {}
    for p in devs:
        h = units.to_internal(1.0, p.unit)
        up_lines = _lines(chain, desc, {p.name: np.array([h])}, 1)
        down_lines = _lines(chain, desc, {p.name: np.array([-h])}, 1)
        up, down = _quantities(desc, up_lines), _quantities(desc, down_lines)
        for key in values:
            grads.setdefault(key, {})[p.name] = float((up[key][0][0] - down[key][0][0]) / 2.0)
        for (element, u), d in zip(_distance_parts(desc, up_lines).items(), _distance_parts(desc, down_lines).values()):
            part_grads.setdefault(element, []).append((p.name, (u[0] - d[0]) / 2.0))
    nominal_gap = _distance_parts(desc, _lines(chain, desc, {}, 1))
    rows = []
    for (element, quantity), (v, unit) in values.items():
        low, high = az.hdi(v, hdi_prob=HDI_PROB)
        g = {k: w for k, w in grads[element, quantity].items() if abs(w) > 1e-15}
        determined = ident.estimable(g)
        if quantity == "pivot_distance" and np.linalg.norm(nominal_gap[element][0]) < 1e-9:
            # |gap| at 0 has no first order: determined only if every component of the gap is
            parts = part_grads[element]
            determined = all(ident.estimable({k: float(w[j]) for k, w in parts if abs(w[j]) > 1e-15})
                             for j in range(len(parts[0][1])))
        rows.append({"element": element, "quantity": quantity, "unit": unit,
                     "nominal": float(nominal[element, quantity][0][0]), "mean": float(v.mean()),
                     "sd": float(v.std(ddof=1)), "hdi_low": float(low), "hdi_high": float(high),
                     "determined": bool(determined)})
    return AxisLines(pd.DataFrame(rows, columns=COLUMNS), desc.configuration, inclined_bases(desc))


def isg_position_errors(result) -> tuple[dict[str, float], list[str]]:
    """The posterior means of the position errors the data determine, by ISG name, in mm and rad
    (:mod:`mtmcal_bayes.io.isg_csv`), and the comments saying what is left out and why: a deviation the data do not
    determine (its value would be the prior's), one determined only in combination (which combination), one the
    format has no name for, one the machine's model does not estimate (the default selection's reason, SPEC §21).
    An inclined rotary axis, whose errors are named in its own basis, is given as its identified line
    (:func:`inclined_lines`)."""
    from ..inference.identifiability import campaign_identifiability
    from ..io.isg_csv import isg_name
    from ..io.machine_reader import description_of

    post = result.log_posterior
    ident = result.identifiability or campaign_identifiability(post)
    in_combination: dict[str, list[str]] = {}
    for c in result.combinations:
        for n in c["weights"]:
            in_combination.setdefault(n, []).append(c["name"])
    desc = description_of(post.campaign.machine)
    inclined = {d.name: d.body for d in generated(desc) if d.body in desc.axes and desc.axes[d.body].inclined}
    values, comments = {}, [f"position errors identified by mtmcal-bayes from {post.campaign.source} "
                            f"({post.model_name} model, posterior means; mm and rad)"]
    for p in post.space.parameters:
        if p.group != "deviation":
            continue
        symbol = p.name if p.name.startswith("E_") else iso_symbol(p.name)
        name = isg_name(symbol) if symbol else None
        carrier = inclined.get(p.name)
        if name is None and carrier is not None:
            comments.append(f"{p.name}: an error of the inclined {carrier} axis in its own basis, which no position "
                            f"error of this format names; {carrier}'s identified line is given instead")
        elif name is None:
            comments.append(f"{p.name}: no position error of this format names it; left out")
        elif p.name in ident.undetermined:
            comments.append(f"{name}: not determined by this campaign (its value would be the prior's); left out")
        elif p.name not in ident.determined:
            comments.append(f"{name}: determined only in combination ({'; '.join(in_combination.get(p.name, []))}); "
                            "left out")
        else:
            values[name] = float(units.to_internal(result.summary.loc[p.name, "mean"], p.unit))
            if carrier is not None:  # an inclined axis' zero keeps its ISO name: a turn about the axis' own line
                comments.append(f"{name}: the zero of the inclined {carrier} axis, a turn about its own line")
    estimated = set(post.space.names)
    why = redundant(desc)
    for d in generated(desc):
        name = isg_name(d.symbol)
        if name is None and d.name in inclined and d.name not in estimated:
            comments.append(f"{d.symbol}: not estimated by the machine's model ({why.get(d.name, 'not selected')}); "
                            f"held at zero in {d.body}'s identified line")
        if name is not None and d.name not in estimated:
            listed = desc.deviations is not None and d.name in desc.deviations
            reason = "not among the quantities its model samples" if listed else why.get(d.name, "not selected")
            comments.append(f"{name}: not estimated by the machine's model ({reason}); held at zero, left out")
    if inclined:
        line_values, line_comments = inclined_lines(result, desc)
        values |= line_values
        comments += line_comments
    return values, comments


def inclined_lines(result, desc: MachineDescription) -> tuple[dict[str, float], list[str]]:
    """Each inclined rotary axis' identified line for the ISG CSV (``PXB PYB PZB``, mm: the line's point nearest
    the described ``point_mm``; ``VXB VYB VZB``: its unit direction; posterior means in the machine frame at the home
    pose, :func:`axis_lines`), with a comment per axis: what the numbers are, a number left out because the data do
    not determine it, and a point fixed by the description (its position errors not estimated: sd 0)."""
    from ..io.isg_csv import line_names

    table = axis_lines(result).table
    values, comments = {}, []
    for ax in desc.rotary_axes:
        if not ax.inclined:
            continue
        rows = table[table["element"] == ax.letter].set_index("quantity")
        names = line_names(ax.letter)
        comments.append(f"{' '.join(n for n, _, _ in names)}: the inclined {ax.letter} axis' identified line "
                        "(a point in mm, the point nearest the described point_mm, and its unit direction; machine "
                        "frame, every axis at 0)")
        fixed = []
        for name, what, c in names:
            row = rows.loc[f"{what}_{c}"]
            if not row["determined"]:
                comments.append(f"{name}: not determined by this campaign (its value would be the prior's); left out")
                continue
            values[name] = float(row["mean"])
            if what == "point" and row["sd"] == 0.0:
                fixed.append(name)
        if fixed:
            comments.append(f"{' '.join(fixed)}: the description's point (the axis' position errors are not "
                            "estimated)")
    return values, comments

