"""Numbers that rest on a choice of reading: each quantity's estimate under the campaign's alternative reading.

Where a campaign's reading of some ball-bar runs was chosen over another (a run's ``alternative_convention``,
docs/campaign-format.md), every quantity shown is estimated under both readings with the exact σ-marginal posterior
of the same model (linearised for a kinematic one), data, dx_BT assumption and σ_model settings
(:meth:`~mtmcal_bayes.analysis.CampaignAnalysis.reading_choice`).  A quantity whose estimate moves by more than its
posterior sd, ``|mean_chosen − mean_alternative| > sd_chosen``, rests on the choice: it is marked :data:`MARK` where
it is shown, with its value under the alternative reading.  Both means and the sd come from the exact posteriors, so
the marks do not depend on the sampler's Monte-Carlo error (the sampled mean and sd agree with them to about 0.03 sd).
"""

from __future__ import annotations

import math

import numpy as np
import pandas as pd

from .. import units

#: the mark of a quantity that rests on the choice of reading
MARK = "†"
#: the summary's columns: the estimate under the alternative reading (display units), its shift from the chosen
#: reading's in posterior sd of the chosen one, and whether it rests on the choice (the shift exceeds one sd)
ALTERNATIVE, SHIFT, RESTS = "reading_alternative", "reading_shift_sd", "rests_on_reading"
COLUMNS = [ALTERNATIVE, SHIFT, RESTS]
#: the head of the column that shows the mark and the value under the alternative reading
HEAD = "rejected reading"


def choice_columns(chosen: dict[str, tuple[float, float]], alternative: dict[str, tuple[float, float]]) -> pd.DataFrame:
    """:data:`COLUMNS` for each quantity of ``chosen`` that ``alternative`` has too; both ``{name: (mean, sd)}`` in
    display units (″, µm), the posterior under the chosen reading and under the alternative one."""
    rows = {}
    for name, (mean, sd) in chosen.items():
        if name not in alternative:
            continue
        alt = float(alternative[name][0])
        move = alt - mean
        shift = move / sd if sd > 0 else (0.0 if move == 0 else math.copysign(math.inf, move))
        rows[name] = {ALTERNATIVE: alt, SHIFT: float(shift), RESTS: bool(abs(move) > sd)}
    out = pd.DataFrame.from_dict(rows, orient="index", columns=COLUMNS)
    out[RESTS] = out[RESTS].astype(bool)
    return out


def has_choice(table: pd.DataFrame) -> bool:
    """Whether a summary carries the columns of a choice of reading."""
    return RESTS in table.columns


def rests(row) -> bool:
    """Whether a summary row's quantity rests on the choice of reading."""
    value = row.get(RESTS, False)
    return isinstance(value, (bool, np.bool_)) and bool(value)  # NaN where the quantity has no alternative


def marked(table: pd.DataFrame) -> list[str]:
    """The quantities of a summary that rest on the choice of reading, in its order."""
    return [n for n, r in table.iterrows() if rests(r)] if has_choice(table) else []


def mark_cell(row, digits: int = 2) -> str:
    """``"† 3.88"`` for a quantity that rests on the choice (its value under the alternative reading), else ``""``."""
    return f"{MARK} {row[ALTERNATIVE]:.{digits}f}" if rests(row) else ""


def alternative_clause(row, decimals: int) -> str:
    """The certificate's addition for a quantity that rests on the choice: ``" † Under the best rejected reading of
    the ball-bar runs the estimate would be 3.9 ″."``; ``""`` for one that does not."""
    if not rests(row):
        return ""
    return (f" {MARK} Under the best rejected reading of the ball-bar runs the estimate would be "
            f"{row[ALTERNATIVE]:.{decimals}f} {units.SYMBOL[row['unit']]}.")


def note(campaign) -> str:
    """One line saying what the mark means on ``campaign``: which runs' reading was chosen, their alternative, why."""
    runs = campaign.ballbar.reading_choices()
    who = ", ".join(r.label for r in runs)
    alt = "; ".join(f"{r.label} read {r.alternative_convention}" for r in runs)
    reason = campaign.ballbar.alternative_reason
    return (f"{MARK} rests on the reading chosen for {who}: under the best rejected reading ({alt}) its estimate moves "
            "by more than its posterior sd, to the value beside the mark (exact σ-marginal posteriors, same model and "
            "data)" + (f". Why this reading: {reason}" if reason else "") + ".")


def short_note() -> str:
    """What the mark means, in one short line, where :func:`note` is shown nearby (docs/metrology.md)."""
    return (f"{MARK} rests on the reading chosen for some ball-bar runs: the value beside it is the estimate under the "
            "best rejected reading (docs/metrology.md)")
