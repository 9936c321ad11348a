"""Posterior sds per machine minute: the R-test against the ball bar and the touch probe on each built-in type
(issue 43 Validation; docs/rtest.md, "Posterior sds per machine minute").

    python bench/rtest_minutes.py [--markdown]

Per type, three campaigns of one instrument each, of equal machine minutes by the time model (machine_time.py), each
simulated (with noise, seed 1) from one stated truth — the type's demo ``[truth]`` (the thesis machine:
tests/data/formats_truth.toml) with every nuisance term 0 — and each given its exact posterior (``sample --sampler
exact``: the linear model, σ_model integrated out):

* **ball bar**: the type's demo ball-bar runs (the thesis campaign's on the thesis type), as measured; their minutes
  M (the machine's clock, measured in canonical order from a new session) set the budget;
* **touch probe**: the demo's probe runs (the thesis campaign's C-axis and B-axis runs), each position probed as
  many times as fit in M (``mount_probe_min`` + positions × repeats × ``probe_position_min``);
* **R-test**: the one-sphere static campaign (tests/rtest_campaigns.py: tool frame, zeroed at the first position,
  one 150 mm nest not calibrated), each position read as many times as fit in M (``mount_rtest_min`` + positions ×
  repeats × (``index_rtest_min`` + ``dwell_rtest_min``)).

Each row: a deviation of the machine's selection, its posterior sd per instrument, ``—`` where that campaign does not
determine it (:func:`campaign_identifiability`: its posterior then rests on its prior).  The budget is filled by
repeats, the simplest equal-minutes rule: repeats shrink the readings' scatter, not the instrument's discrepancy
scale, which does not average out.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import mtmcal_bayes as mb  # noqa: E402
from mtmcal_bayes import units  # noqa: E402
from mtmcal_bayes.campaign import Probe, Truth  # noqa: E402
from mtmcal_bayes.datasets import builtin_campaign_text  # noqa: E402
from mtmcal_bayes.inference.identifiability import campaign_identifiability  # noqa: E402
from mtmcal_bayes.inference.log_posterior import LogPosterior  # noqa: E402
from mtmcal_bayes.io.campaign_reader import load_truth, parse_campaign  # noqa: E402
from mtmcal_bayes.io.machine_reader import demo_campaign  # noqa: E402
from mtmcal_bayes.machine_time import TimeModel, canonical_order, probe_run_minutes, rtest_run_minutes  # noqa: E402
from mtmcal_bayes.planning.candidates import Candidate  # noqa: E402
from mtmcal_bayes.planning.chain_candidates import arc_spec  # noqa: E402
from mtmcal_bayes.planning.machine_kit import kit_of  # noqa: E402
from mtmcal_bayes.simulation.simulate import synthetic_campaign  # noqa: E402
from tests.rtest_campaigns import static_text  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TYPES = ("integrex-i200", "vertical-turn-mill", "trunnion", "head-head", "nutating-head")
SEED = 1
INSTRUMENTS = ("ballbar", "probe", "rtest")
LABEL = {"ballbar": "ball bar", "probe": "touch probe", "rtest": "R-test"}


def base_campaign(machine: str):
    """The type's demo campaign (the thesis campaign on the thesis type) and its stated truth, nuisance terms 0."""
    path = demo_campaign(machine)
    c = parse_campaign(builtin_campaign_text()[0]) if path is None else mb.load_campaign(path)
    truth = load_truth(ROOT / "tests" / "data" / "formats_truth.toml", c) if c.truth is None else c.truth
    return c, Truth(dict(truth.deviations))


class _Timed:
    """A measured ball-bar run as the machine's clock takes it: pattern, set-up, mount, repeats and its candidate
    (the engine's clock times a run over its arc with its held axes)."""

    def __init__(self, c, r):
        bb = c.ballbar
        self.pattern, self.setup, self.mount = r.pattern, bb.setups[r.setup], bb.mounts[r.mount]
        self.repeats = len(next(iter(r.repeats.values())))
        self.candidate = Candidate(r.pattern, "measured", r.pattern, self.setup, self.mount, bb.length, self.repeats,
                                   arc_deg=arc_spec(r.arc_deg), hold_deg=tuple((r.hold_deg or {}).items()))


def ballbar_minutes(c, model: TimeModel) -> float:
    """Minutes of ``c``'s ball-bar runs, measured in canonical order from a new session."""
    runs = [_Timed(c, r) for r in c.ballbar.runs]
    clock = kit_of(c).clock(model, c)
    return clock.total([runs[i] for i in canonical_order(runs)])


def _repeats_within(budget: float, minutes_of) -> int:
    """The most repeats (at least 1) whose minutes ``minutes_of(r)`` stay within ``budget``."""
    r = 1
    while minutes_of(r + 1) <= budget:
        r += 1
    return r


def campaigns(machine: str, model: TimeModel) -> dict:
    """``{instrument: (campaign simulated from the truth, minutes)}`` of equal budgets (module docstring)."""
    c, truth = base_campaign(machine)
    budget = ballbar_minutes(c, model)
    ballbar = synthetic_campaign(_only(c, "ballbar"), truth, "linear", noise=True, seed=SEED)
    probe = _only(c, "probe")
    k = sum(run.positions for run in probe.probe.runs)
    rp = _repeats_within(budget, lambda r: probe_run_minutes(model, k, r))
    rt = parse_campaign(static_text(machine))
    n = sum(run.positions for run in rt.rtest.runs)
    rr = _repeats_within(budget, lambda r: rtest_run_minutes(model, n, r))
    return {"ballbar": (ballbar, budget),
            "probe": (synthetic_campaign(probe, truth, "linear", noise=True, seed=SEED, repeats=rp),
                      probe_run_minutes(model, k, rp)),
            "rtest": (synthetic_campaign(rt, truth, "linear", noise=True, seed=SEED, repeats=rr),
                      rtest_run_minutes(model, n, rr))}


def _only(c, instrument: str):
    """A copy of ``c`` with one instrument's runs."""
    import copy

    out = copy.deepcopy(c)
    if instrument != "ballbar":
        out.ballbar.runs = []
    if instrument != "probe":
        out.probe = Probe()
    out.rtest = None
    return out


def table(machine: str, model: TimeModel | None = None) -> tuple[dict, list[dict]]:
    """The minutes per instrument and per deviation its posterior sd per instrument (None: not determined)."""
    model = model or TimeModel()
    made = campaigns(machine, model)
    rows: dict[str, dict] = {}
    unit = {}
    for instrument, (c, _) in made.items():
        post = mb.sample(c, sampler="exact", data=instrument, seed=SEED)
        ident = campaign_identifiability(LogPosterior(c, "linear", data=instrument))
        for q in ident.deviations:
            row = post.summary.loc[q]
            rows.setdefault(q, {})[instrument] = float(row["sd"]) if q in ident.determined else None
            unit[q] = row.get("unit", "")
    return {i: m for i, (_, m) in made.items()}, [{"deviation": q, "unit": unit[q], **v} for q, v in rows.items()]


def markdown(machine: str, minutes: dict, rows: list[dict]) -> str:
    head = " | ".join(f"{LABEL[i]} ({minutes[i]:.0f} min)" for i in INSTRUMENTS)
    out = [f"| `{machine}` | {head} |", "|---|" + "---|" * len(INSTRUMENTS)]
    for r in rows:
        cells = " | ".join("—" if r.get(i) is None else f"{r[i]:.3g}" for i in INSTRUMENTS)
        out.append(f"| `{r['deviation']}` ({units.SYMBOL.get(r['unit'], r['unit'])}) | {cells} |")
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--markdown", action="store_true", help="the tables as docs/rtest.md holds them")
    a = ap.parse_args()
    for machine in TYPES:
        minutes, rows = table(machine)
        if a.markdown:
            print(markdown(machine, minutes, rows) + "\n")
            continue
        print(f"{machine}: " + ", ".join(f"{LABEL[i]} {minutes[i]:.1f} min" for i in INSTRUMENTS))
        for r in rows:
            print(f"  {r['deviation']:12s} {r['unit']:7s} " + "  ".join(
                f"{LABEL[i]:>11s} {'—' if r.get(i) is None else format(r[i], '.3g'):>7s}" for i in INSTRUMENTS))


if __name__ == "__main__":
    main()
