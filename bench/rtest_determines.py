"""What a one-sphere static R-test campaign determines on each built-in type (docs/rtest.md, "What a one-sphere
static R-test campaign determines").

    python bench/rtest_determines.py

The campaign (tests/rtest_campaigns.py: :func:`static_runs`): one sphere at a stated position on the table, one nest
(150 mm, not calibrated), each rotary axis indexed alone over its travel with the others at 0, then each at 4
positions with the others held; the runs all in one frame and zero, for each of the four settings.  What it
determines is :func:`~mtmcal_bayes.inference.identifiability.campaign_identifiability` of the R-test data alone (the
rule every output uses) over the machine's default selection of deviations.  Prints the Markdown tables
docs/rtest.md holds (tests/test_rtest_validation.py checks they are equal).
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mtmcal_bayes.inference.identifiability import campaign_identifiability  # noqa: E402
from mtmcal_bayes.inference.log_posterior import LogPosterior  # noqa: E402
from tests.rtest_campaigns import SETTINGS, SPHERES, static_campaign, static_runs  # noqa: E402

TYPES = ("integrex-i200", "vertical-turn-mill", "trunnion", "head-head", "nutating-head")


def verdicts(machine: str) -> dict:
    """Per setting (frame, zero): the :class:`~mtmcal_bayes.inference.identifiability.Identifiability` of the
    one-sphere static campaign's R-test data."""
    return {s: campaign_identifiability(LogPosterior(static_campaign(machine, *s), "linear", data="rtest"))
            for s in SETTINGS}


def _cell(ident, name: str) -> str:
    if name in ident.determined:
        return "determined"
    if name in ident.undetermined:
        return "not determined"
    return "; ".join(f"in `{c.name}`" for c in ident.combinations if name in c.weights)


def table(machine: str) -> str:
    """The Markdown table of ``machine``: one row per deviation of its default selection, one column per setting."""
    by = verdicts(machine)
    first = next(iter(by.values()))
    head = "| deviation | " + " | ".join(f"`{f}`, `{z}`" for f, z in SETTINGS) + " |"
    rows = [head, "|---" * (len(SETTINGS) + 1) + "|"]
    for name in first.deviations:
        rows.append(f"| `{name}` | " + " | ".join(_cell(by[s], name) for s in SETTINGS) + " |")
    return "\n".join(rows)


def runs(machine: str) -> str:
    """The runs of ``machine``'s campaign, one line."""
    def angles(run):
        return ", ".join(f"{a} {' '.join(f'{v:g}' for v in vals)}" for a, vals in run["angles"].items())

    return "; ".join(f"{r['id']}: {angles(r)}" for r in static_runs(machine, "tool", "first"))


def main() -> None:
    for machine in TYPES:
        sphere, why = SPHERES[machine]
        print(f"### `{machine}`\n\nsphere {sphere} mm ({why}); runs (°): {runs(machine)}\n\n{table(machine)}\n")


if __name__ == "__main__":
    main()
