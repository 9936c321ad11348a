"""design.html: the schedule as a time line, the sds before and after, why each run is there."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

from ..figure_style import label, new_figure, save_png
from ..html_page import Page
from ..version import __version__
from .design_problem import PROMISE

EVENT_COLOURS = {"mount ball bar": "#555555", "tool change": "#E69F00", "re-clamp W ball": "#CC79A7",
                 "pattern change": "#BBBBBB", "measure": "#0072B2"}
#: the set-up changes of the touch probe and the R-test, in the legend where a design has them
OTHER_EVENT_COLOURS = {"change instrument": "#D55E00", "mount probe": "#009E73", "stylus change": "#999933",
                       "move sphere": "#882255", "mount R-test": "#56B4E9"}
TIMELINE_CAPTION = (
    "The designed campaign on the machine's clock: each measuring run (blue, numbered in measuring order) and "
    "the set-up changes before it — mounting the ball bar, changing the tool length and re-centring the T ball, "
    "re-clamping the W ball, re-seating the bar for the next pattern; for touch-probe and R-test runs, changing "
    "the instrument, mounting the probe or the R-test nest, changing the stylus, moving the sphere — from the time "
    "model of docs/design.md.")
SD_CAPTION = (
    "Posterior sd of each quantity today (grey bar) and after measuring the design: the mean over simulated "
    "machines (dot) and its 10–90 % spread (line), from the exact σ-marginal posterior of each simulated campaign; "
    "black ticks: the targets. Log scale.")


def timeline_figure(events, runs):
    fig, ax = new_figure(figsize=(11, 3.0))
    colours = EVENT_COLOURS | OTHER_EVENT_COLOURS
    kinds = list(EVENT_COLOURS) + [k for k in OTHER_EVENT_COLOURS if any(e.kind == k for e in events)]
    for e in events:
        y = 1 if e.kind == "measure" else 0
        ax.broken_barh([(e.start_min, e.minutes)], (y - 0.35, 0.7), facecolors=colours.get(e.kind, "0.5"),
                       edgecolor="white", linewidth=0.6)
        if e.kind == "measure" and e.run_index is not None and e.minutes > 0:
            ax.text(e.start_min + e.minutes / 2, y, str(e.run_index + 1), ha="center", va="center", color="white",
                    fontsize=8)
    ax.set_yticks([0, 1], ["set-up", "measuring"])
    ax.set_xlabel("machine time, min")
    end = max((e.start_min + e.minutes for e in events), default=0.0)
    ax.set_xlim(0, max(end, 1.0) * 1.01)  # an empty design still gets an axis
    if not runs:
        ax.text(0.5, 0.5, "no run designed (the notes say why)", transform=ax.transAxes, ha="center",
                va="center", fontsize=10, color="0.3")
    ax.set_ylim(-0.7, 1.7)
    from matplotlib.patches import Patch

    ax.legend(handles=[Patch(color=colours[k], label=k) for k in kinds], ncol=5, fontsize=8, loc="upper center",
              bbox_to_anchor=(0.5, -0.26), frameon=False)
    ax.set_title(f"{len(runs)} run{'s' * (len(runs) != 1)}, {end:.0f} machine minutes", fontsize=10)
    return fig


def sd_figure(design):
    chk = design.check
    t = design.targets
    fig, axes = new_figure(1, len(t), figsize=(1.5 * len(t) + 1.2, 3.4), squeeze=False)
    fig.subplots_adjust(wspace=0.55)
    p10, p90 = chk.sd_quantile(0.1), chk.sd_quantile(0.9)
    for i, ax in enumerate(axes[0]):
        ax.bar([0], [chk.sd_now[i]], color="0.8", width=0.6)
        ax.plot([1], [chk.sd_mean[i]], "o", color="#0072B2")
        ax.plot([1, 1], [p10[i], p90[i]], "-", color="#0072B2", lw=2)
        if np.isfinite(design.goal.targets[i]):
            ax.axhline(design.goal.targets[i], color="black", lw=1.2, ls="--")
        ax.set_yscale("log")
        ax.yaxis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
        ax.yaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        shown = [chk.sd_now[i], p10[i], p90[i]] + ([design.goal.targets[i]] if np.isfinite(design.goal.targets[i])
                                                   else [])
        ax.set_ylim(min(shown) / 1.6, max(shown) * 1.6)
        ax.yaxis.set_minor_formatter(NullFormatter())
        ax.set_xticks([0, 1], ["now", "after"], fontsize=8)
        ax.set_xlim(-0.6, 1.6)
        ax.set_title(label(t[i]), fontsize=8)
        ax.tick_params(axis="y", labelsize=7)
    return fig


def _sigma_sentence(reached: bool, learnt: bool = False) -> str:
    """Whether σ_model is then set by knowledge (the data; or they and a prior ``learnt`` elsewhere) or by the
    assumption."""
    if learnt:
        return ("the learnt prior and the data, not an assumption, then set σ_model." if reached else
                "σ_model is not yet known as well as the goal asks.")
    return "the data, not the prior, then set σ_model." if reached else "σ_model still rests mostly on its prior."


def write_design_html(design, out_dir, *, doc: dict, runs: pd.DataFrame, expected: pd.DataFrame) -> list[str]:
    """Write the figures and design.html into ``out_dir`` (``doc`` the design's JSON, ``runs`` and ``expected`` its
    tables); returns the files written."""
    out = Path(out_dir)
    events = design.timing.events(design.runs, design.start)
    fig = timeline_figure(events, design.runs)
    save_png(fig, out / "design_timeline.png")
    fig = sd_figure(design)
    save_png(fig, out / "design_sd.png")
    page = Page("Designed calibration campaign")
    page.section("summary", "Summary")
    sig = doc["sigma_model"]
    met = doc["probability_targets_met"]
    page.box("statement", "What measuring this design gives", [
        f"{len(design.runs)} runs in {doc['total_minutes']:.0f} machine minutes, set-up changes included.",
        f"σ_model contraction {sig['contraction_before']:.2f} today → {sig['contraction_after']:.2f} expected"
        + (f" (target {sig['target']:g})" if sig["target"] is not None else "") + ": "
        + (_sigma_sentence(sig["contraction_after"] >= 0.5) if "prior_source" not in sig else
           f"measured against the {sig['contraction_reference']['which']} prior "
           f"{sig['contraction_reference']['prior']} (the wider), σ_model's prior "
           f"{sig['prior']} being learnt elsewhere ({sig['prior_source']['from']}): "
           + _sigma_sentence(sig["contraction_after"] >= 0.5, learnt=True)),
        (f"Every target met in {met:.0%} of simulated machines; each target alone in at least {PROMISE:.0%} "
         "(the design's promise)." if np.isfinite(design.goal.targets).any() else
         "No sd targets: the design is for σ_model's contraction (and the budget)."),
    ])
    page.section("schedule", "Schedule")
    page.figure(out / "design_timeline.png", TIMELINE_CAPTION, "time line of the designed campaign")
    if "R_C_mm" in runs:
        where = ["R_C_mm"]
    else:  # a described machine's: the W ball, the arc and the held axes as a reader writes them
        # a probe or R-test run has none of them (its stylus or nest and sphere are its set-up and mount)
        runs = runs.assign(
            position_mm=[", ".join(f"{x:g}" for x in v) if isinstance(v, list) else "—" for v in runs["position_mm"]],
            arc_deg=[f"{v[0]:g}…{v[1]:g}° by {v[2]:g}°" if isinstance(v, list) else "—" for v in runs["arc_deg"]],
            hold_deg=[", ".join(f"{k} {v:g}°" for k, v in h.items()) or "—" if isinstance(h, dict) else "—"
                      for h in runs["hold_deg"]])
        where = ["position_mm", "arc_deg", "hold_deg"]
    page.table(runs[["pattern", "setup", "mount", "R_B_mm", *where, "repeats", "minutes", "program", "why"]],
               digits={"R_B_mm": 1, "R_C_mm": 0, "minutes": 1})
    page.section("expected", "Expected uncertainty")
    page.figure(out / "design_sd.png", SD_CAPTION, "sd before and after the design")
    page.table(expected, digits=2)
    page.section("notes", "How this was computed")
    page.box("missing", "Notes", design.notes)
    page.write(out / "design.html", f"mtmcal-bayes {__version__} · design of {design.campaign.source}")
    return ["design.html", "design_timeline.png", "design_sd.png"]


__all__ = ["write_design_html", "timeline_figure", "sd_figure"]
