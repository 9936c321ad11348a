"""What ``design`` and ``next`` print and write: JSON, text, the campaign to fill in, NC programs, design.html."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pandas as pd

from .. import units
from ..campaign import DesignGoal, PlannedRun
from .design_make import Design
from .design_problem import PROMISE
from .design_other_runs import FILL_IN, fill_in_tables, measured_ids, other_program_name, other_record, run_id
from .design_runs import geometry_of
from .run_records import program_name
from .machine_kit import kit_of
from .next_run import NextStep


def _num(v) -> float | None:
    v = float(v)
    return v if math.isfinite(v) else None


def run_columns(design: Design) -> list[str]:
    return kit_of(design.campaign).run_columns


def run_records(design: Design, programs: bool = False) -> list[dict]:
    """The ``runs`` of ``design --json``, in measuring order: the ball bar's as the machine's planning kit writes
    them, then the probe's and the R-test's (:func:`.design_other_runs.other_record`)."""
    bar = [i for i, r in enumerate(design.runs) if r.instrument == "ballbar"]
    if len(bar) == len(design.runs):
        return kit_of(design.campaign).run_records(design, programs)
    view = copy.copy(design)  # the ball bar's runs come first in measuring order: their records keep their order
    view.runs, view.minutes, view.why = ([x[i] for i in bar] for x in (design.runs, design.minutes, design.why))
    out = kit_of(design.campaign).run_records(view, programs)
    return out + [other_record(design.campaign, i, r, minutes=m, why=why, programs=programs)
                  for i, (r, m, why) in enumerate(zip(design.runs, design.minutes, design.why), start=1)
                  if r.instrument != "ballbar"]


def _where(rec: dict) -> str:
    """The geometry of a run record, for the text: the thesis' lever arms, or a described machine's W ball, arc and
    held axes."""
    if "position_mm" not in rec:
        return f"R_B {rec['R_B_mm']:.1f} mm, R_C {rec['R_C_mm']:.0f} mm"
    x, y, z = rec["position_mm"]
    lo, hi, _ = rec["arc_deg"]
    held = "".join(f", {a} at {v:g}°" for a, v in rec["hold_deg"].items())
    return f"R_B {rec['R_B_mm']:.1f} mm, W ({x:g}, {y:g}, {z:g}) mm, {lo:g}…{hi:g}°{held}"


def _determined(design: Design) -> np.ndarray:
    """(t,) whether the campaign plus the designed runs determine each quantity."""
    return np.ones(len(design.targets), bool) if design.determined is None else np.asarray(design.determined, bool)


def expected(design: Design) -> dict:
    """``expected`` of ``design --json``: per quantity the sd today and after the design (mean, 10–90 %), and
    whether the runs determine it; the share of machines meeting a target only for a determined quantity (a
    target met by the prior alone is not met: ``share_met`` null)."""
    chk = design.check
    p10, p90 = chk.sd_quantile(0.1), chk.sd_quantile(0.9)
    determined = _determined(design)
    share = np.where(determined, chk.share_met(design.goal.targets), np.nan)
    out = {}
    for i, (t, u) in enumerate(zip(design.targets, design.target_units)):
        out[t] = {"unit": units.SYMBOL[u], "sd_before": _num(chk.sd_now[i]), "sd_after": _num(chk.sd_mean[i]),
                  "sd_after_p10": _num(p10[i]), "sd_after_p90": _num(p90[i]),
                  "target": _num(design.goal.targets[i]), "share_met": _num(share[i]),
                  "sd_after_closed_form": _num(design.closed_form["sd_promised"][i]),
                  "determined": bool(determined[i])}
    return out





def design_document(design: Design, campaign_path: str | None = None, programs: bool = False) -> dict:
    """``design --json``."""
    c = design.check.contraction
    return {"runs": run_records(design, programs), "total_minutes": round(design.total_minutes, 2),
            "expected": expected(design),
            "sigma_model": {"contraction_before": design.check.contraction_now,
                            "contraction_after": float(c.mean()) if c.size else design.check.contraction_now,
                            "contraction_after_p10": float(np.quantile(c, 0.1)) if c.size else None,
                            "contraction_after_p90": float(np.quantile(c, 0.9)) if c.size else None,
                            "target": design.goal.contraction} | design.learnt,
            "budget_min": design.goal.budget, "promise": PROMISE,
            "probability_targets_met": design.probability_targets_met(),
            "schedule": [e.__dict__ | {} for e in design.timing.events(design.runs, design.start)],
            "check_kinematics": None if design.check.kinematics is None else design.check.kinematics.document(),
            "model": design.model, "notes": design.notes, "not_targeted": design.not_targeted,
            "campaign": campaign_path}


def design_text(design: Design) -> str:
    """What ``design`` prints."""
    lines = [f"designed campaign: {len(design.runs)} run(s), {design.total_minutes:.0f} machine minutes "
             f"(set-up changes included)", ""]
    for rec in run_records(design):
        if "instrument" in rec:  # a probe or R-test run
            lines.append(f"{rec['order']:>3}. {rec['candidate']}: {rec['setup']}, {rec['mount']}, {rec['repeats']}× "
                         f"{rec['minutes']:6.1f} min  {rec['why']}")
            continue
        lines.append(f"{rec['order']:>3}. {rec['pattern']:<3} setup {rec['setup']:<10} mount {rec['mount']:<12} "
                     f"{_where(rec)}, {rec['repeats']}× "
                     f"{rec['minutes']:6.1f} min  {rec['why']}")
    lines += ["", f"{'quantity':<18} {'sd now':>9} {'after':>9} {'10–90 %':>17} {'target':>8} {'met in':>7}"]
    for t, e in expected(design).items():
        tg = "" if e["target"] is None else f"{e['target']:.3g}"
        share = "" if e["share_met"] is None else f"{e['share_met']:.0%}"
        if not e["determined"]:
            share = "not determined"
        u = f"{e['unit']:<2}"
        lines.append(f"{t:<18} {e['sd_before']:>7.3g} {u} {e['sd_after']:>6.3g} {u} "
                     f"{e['sd_after_p10']:>7.3g}–{e['sd_after_p90']:<6.3g} {u} {tg:>6} {share:>7}")
    if design.not_targeted:
        lines += ["", "not targeted (no reported quantity of their own):"]
        lines += [f"  {d}: {why}" for d, why in design.not_targeted.items()]
    c = design.check.contraction
    ctext = f"{c.mean():.2f}" if c.size else "unchanged"
    lines += ["", f"σ_model contraction: {design.check.contraction_now:.2f} now → {ctext} after"
              + (f" (target {design.goal.contraction:g})" if design.goal.contraction is not None else "")
              + _against(design.learnt)]
    if design.check.kinematics is not None and design.check.kinematics.line():
        lines.append(design.check.kinematics.line())
    lines += [f"note: {n}" for n in design.notes]
    return "\n".join(lines)


def _against(learnt: dict) -> str:
    """What the contraction is measured against, under a σ_model prior learnt elsewhere (empty otherwise)."""
    if not learnt:
        return ""
    ref = learnt["contraction_reference"]
    return (f", against the {ref['which']} prior {ref['prior']} (the wider); σ_model's prior "
            f"{learnt['prior']} learnt elsewhere, from {learnt['prior_source']['from']}")


def designed_campaign(design: Design, goal: DesignGoal | None = None):
    """The starting campaign plus the designed runs as planned runs in measuring order, and the ``[design]`` goal."""
    base = design.campaign
    out = copy.copy(base)
    bb = copy.copy(base.ballbar)
    bb.setups, bb.mounts = geometry_of(base, design.runs)
    bar = [(i, r, m, why) for i, (r, m, why) in enumerate(zip(design.runs, design.minutes, design.why), start=1)
           if r.instrument == "ballbar"]  # the probe's and the R-test's: to_fill_in.toml (write_design)
    bb.planned = [PlannedRun(r.pattern, r.setup.id, r.mount.id, r.repeats, minutes=round(m, 1), why=why, order=i)
                  for i, r, m, why in bar]
    kit = kit_of(base)
    for p, (_, r, _, _) in zip(bb.planned, bar):  # what else a planned run records (a described one: arc, held axes)
        kit.planned_geometry(p, r.candidate, base)
    out.ballbar = bb
    targets = {t: float(v) for t, v in zip(design.targets, design.goal.targets) if np.isfinite(v)}
    out.design = copy.copy(goal) if goal is not None else DesignGoal(targets, design.goal.contraction,
                                                                      design.goal.budget, {})
    # the probe's and the R-test's runs: their tables in to_fill_in.toml, named here so that `next` knows them; a
    # re-plan without ball-bar runs keeps naming the designed runs measured before it (the session goes on with the
    # probe or the R-test: the last of them is the machine's state, next_run.machine_state)
    fill = {run_id(base, i, r): r.label for i, r in enumerate(design.runs, start=1) if r.instrument != "ballbar"}
    done = set(measured_ids(base))
    before = base.design.to_fill_in if base.design is not None and not bar else {}
    out.design.to_fill_in = {k: v for k, v in before.items() if k in done} | fill
    return out


def write_design(design: Design, out_dir, *, program, times: dict | None = None,
                 other_program=None) -> tuple[list[str], str]:
    """Write design.json, campaign.toml, programs/NN_<pattern>.nc and design.html into ``out_dir``; ``program``
    (campaign, planned run) -> NC text; with probe or R-test runs, their programs (``other_program(campaign,
    candidate) -> NC text``) and to_fill_in.toml, their tables (:mod:`.design_other_runs`).  Returns the files
    written (relative) and the campaign's path."""
    from ..io.campaign_writer import save_campaign
    from ..io.json_text import json_text
    from ..io.textfiles import atomic_directory
    from .design_figures import write_design_html

    out = Path(out_dir)
    goal = DesignGoal({t: float(v) for t, v in zip(design.targets, design.goal.targets) if np.isfinite(v)},
                      design.goal.contraction, design.goal.budget, dict(times or {}))
    camp = designed_campaign(design, goal)
    path = out / "campaign.toml"
    files = []
    with atomic_directory(out) as tmp:  # all of it or nothing (programs/ replaced whole: no earlier design's left)
        (tmp / "programs").mkdir()
        for i, (r, p) in enumerate(zip(design.runs, camp.ballbar.planned), start=1):
            (tmp / program_name(i, r.pattern)).write_text(program(camp, p), encoding="utf-8")
            files.append(program_name(i, r.pattern))
        others = [(i, r) for i, r in enumerate(design.runs, start=1) if r.instrument != "ballbar"]
        for i, r in others:
            (tmp / other_program_name(i, r)).write_text(other_program(design.campaign, r.measured), encoding="utf-8")
            files.append(other_program_name(i, r))
        if others:
            from ..io.tomlio import dumps

            (tmp / FILL_IN).write_text(
                "# The designed touch-probe and R-test runs of design.json, in measuring order: measure each with its\n"
                "# program, fill in its readings (centres_mm: repeats x positions x 3; displacement_um likewise) and\n"
                "# add its table to campaign.toml.\n" + dumps(fill_in_tables(design.campaign, others)),
                encoding="utf-8")
            files.append(FILL_IN)
        save_campaign(camp, tmp / "campaign.toml", header="designed by mtmcal-bayes design: fill in each planned run "
                      "once measured (delete planned and repeats, give ex_um/ey_um/ez_um), then run mtmcal-bayes next")
        files.insert(0, "campaign.toml")
        doc = design_document(design, str(path), programs=True)
        (tmp / "design.json").write_text(json_text(doc) + "\n", encoding="utf-8")
        files.insert(0, "design.json")
        runs = pd.DataFrame(run_records(design, programs=True), columns=run_columns(design)).set_index("order")
        files += write_design_html(design, tmp, doc=doc, runs=runs, expected=expected_table(design))
    return files, str(path)


def next_document(step: NextStep, program: str | None = None) -> dict:
    """``next --json``."""
    exp = {}
    after = expected(step.design) if step.design is not None else {}
    for i, (t, u) in enumerate(zip(step.targets, step.target_units)):
        e = {"unit": units.SYMBOL[u], "sd_now": _num(step.sd_now[i]), "target": _num(step.target_sd[i]),
             "determined_now": None if step.determined_now is None else bool(step.determined_now[i])}
        if t in after:
            e.update({k: after[t][k] for k in ("sd_after", "sd_after_p10", "sd_after_p90")})
        exp[t] = e
    run = None
    if step.design is not None and step.design.runs:
        run = run_records(step.design)[0]
        run["program"] = program
    return {"status": step.status, "run": run, "minutes_left": round(step.minutes_left, 2),
            "probability_targets_met": step.probability_targets_met, "expected": exp,
            "sigma_model": {"contraction_now": step.contraction_now, "target": step.contraction_target,
                            "contraction_after": (float(step.design.check.contraction.mean())
                                                  if step.design is not None and step.design.runs else None)}
            | step.learnt,
            "measured_runs": step.measured, "planned_left": step.planned_left, "dropped": step.dropped,
            "added": step.added}


def next_text(step: NextStep) -> str:
    """What ``next`` prints."""
    lines = []
    if step.status == "stop":
        lines.append(f"stop: every target reached (probability {step.probability_targets_met:.0%} over σ_model's "
                     f"posterior) after {step.measured} measured run(s)")
        if step.planned_left:
            lines.append(f"planned runs not needed: {', '.join(step.planned_left)}")
        if step.contraction_target is not None and step.contraction_now < step.contraction_target:
            lines.append(f"σ_model's contraction {step.contraction_now:.2f}, short of {step.contraction_target:g}: the "
                         "designed plan, which promised it in expectation over machines, has been measured in full")
    else:
        r = run_records(step.design)[0]
        if "instrument" in r:  # a probe or R-test run: its table in to_fill_in.toml once written (-o)
            lines.append(f"measure next: {r['candidate']} ({r['setup']}, {r['mount']}), {r['repeats']} repeat(s), "
                         f"~{r['minutes']:.0f} min — {r['why']}")
        else:
            where = (f"{r['setup']} (R_B {r['R_B_mm']:.1f} mm), mount {r['mount']} (R_C {r['R_C_mm']:.0f} mm)"
                     if "R_C_mm" in r else f"{r['setup']}, mount {r['mount']} ({_where(r)})")
            lines.append(f"measure next: {r['pattern']} at setup {where}, {r['repeats']} repeats, "
                         f"~{r['minutes']:.0f} min — {r['why']}")
        lines.append(f"time left: {step.minutes_left:.0f} min for {len(step.design.runs)} run(s); every target met "
                     f"at the end in {step.probability_targets_met:.0%} of simulated machines")
        if step.dropped:
            lines.append(f"dropped from the plan: {', '.join(step.dropped)}")
        if step.added:
            lines.append(f"added to the plan: {', '.join(step.added)}")
    lines.append("")
    lines.append(f"{'quantity':<18} {'sd now':>10} {'target':>10}")
    for i, t in enumerate(step.targets):
        u = units.SYMBOL[step.target_units[i]]
        tg = "" if not np.isfinite(step.target_sd[i]) else f"{step.target_sd[i]:.3g} {u:<2}"
        undetermined = step.determined_now is not None and not step.determined_now[i]
        lines.append(f"{t:<18} {step.sd_now[i]:>7.3g} {u:<2} {tg:>10}" + ("  not determined yet" if undetermined
                                                                           else ""))
    lines.append(f"σ_model contraction now {step.contraction_now:.2f}"
                 + (f" (target {step.contraction_target:g})" if step.contraction_target is not None else "")
                 + _against(step.learnt))
    return "\n".join(lines)


def expected_table(design: Design) -> pd.DataFrame:
    """The before/after table of design.html."""
    rows = []
    for t, e in expected(design).items():
        rows.append({"quantity": t, "unit": e["unit"], "sd now": e["sd_before"], "sd after (mean)": e["sd_after"],
                     "10 %": e["sd_after_p10"], "90 %": e["sd_after_p90"], "target": e["target"],
                     "met in": e["share_met"]})
    return pd.DataFrame(rows).set_index("quantity")



class DesignResult:
    """The result of ``design``: :attr:`design`, and where it was written (``-o``)."""

    def __init__(self, design: Design, output: str | None = None, files=(), campaign: str | None = None):
        self.design, self.output, self.files, self.campaign = design, output, list(files), campaign

    def to_json(self) -> dict:
        return {**design_document(self.design, self.campaign, programs=self.output is not None),
                "output": self.output, "files": self.files}

    def to_text(self) -> str:
        text = design_text(self.design)
        if self.output:
            text += f"\n\ndesign written to {self.output}/: {', '.join(self.files)}"
        return text


class NextResult:
    """The result of ``next``: :attr:`step`, and the re-planned campaign and program when written (``-o``)."""

    def __init__(self, step: NextStep, output: str | None = None, files=(), program: str | None = None):
        self.step, self.output, self.files, self.program = step, output, list(files), program

    def to_json(self) -> dict:
        return {**next_document(self.step, self.program), "output": self.output, "files": self.files}

    def to_text(self) -> str:
        text = next_text(self.step)
        if self.output:
            text += f"\n\nwritten to {self.output}/: {', '.join(self.files)}"
        return text


def write_next(step: NextStep, out_dir, *, program, times: dict | None = None,
               other_program=None) -> tuple[list[str], str | None]:
    """The re-planned campaign (measured runs, then the re-planned runs) and the programs in ``out_dir``."""
    if step.design is None:
        return [], None
    files, _ = write_design(step.design, out_dir, program=program, times=times, other_program=other_program)
    if not step.design.runs:
        return files, None
    first = step.design.runs[0]
    name = program_name(1, first.pattern) if first.instrument == "ballbar" else other_program_name(1, first)
    return files, str(Path(out_dir) / name)


__all__ = ["DesignResult", "NextResult", "write_next", "design_document", "design_text", "designed_campaign", "write_design", "next_document", "next_text",
           "run_records", "run_columns", "expected", "expected_table", "program_name"]
