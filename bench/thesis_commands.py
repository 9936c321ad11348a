"""The thesis machine's commands as their users see them, written to a folder to compare two trees byte for byte:
every pattern's ncgen program (three campaign variants: as published, CR outside the W ball, R_C 150 mm; eight option
sets; standalone programs) and, for the catalogue and a grid of candidates, the span rule's verdict and the clock's
minutes (repr: every bit).

    PYTHONPATH=TREE python bench/thesis_commands.py OUT      # then: diff -r OUT_A OUT_B
"""
import copy
import sys
from pathlib import Path

from mtmcal_bayes import api
from mtmcal_bayes.api import campaign_of
from mtmcal_bayes.campaign import Mount, Setup
from mtmcal_bayes.machine_time import TimeModel
from mtmcal_bayes.patterns import PATTERNS
from mtmcal_bayes.planning.design_timing import _AsRun
from mtmcal_bayes.planning.machine_kit import catalogue_of, feasibility_of, kit_of

out = Path(sys.argv[1]); out.mkdir(parents=True, exist_ok=True)
thesis = campaign_of(None)
plus = copy.deepcopy(thesis); plus.ballbar.cr_geometry = "RC+LB"
wide = copy.deepcopy(thesis); wide.ballbar.mounts["C"].R_C = 150.0
lines = []
for name, c in (("thesis", thesis), ("rcplus", plus), ("rc150", wide)):
    for p in PATTERNS:
        for kw in ({}, {"setup": "RB2"}, {"mount": "C"}, {"mount": "B"}, {"step_deg": 9.0, "n": 11, "feed": 2000.0},
                   {"start": (-390.0, 0.0, -112.2605)}, {"R_B_mm": 300.0}, {"step_deg": 1.0}):
            key = f"{name}-{p}-" + "-".join(f"{k}{v}" for k, v in kw.items())
            (out / f"{key}.nc").write_text(api.ncgen(p, campaign=c, **kw))
    kit = kit_of(c)
    fits = feasibility_of(c)
    clock = kit.clock(TimeModel(), c)
    for cand in catalogue_of(c):
        ok, why = fits(cand)
        lines.append(f"{name} {cand.name}: {ok} {why} {clock.run_minutes(_AsRun(cand))!r}")
    for e in (0.0, 100.0, 500.0):
        for p in PATTERNS:
            for R_C in (0.0, 50.0, 100.0, 400.0):
                cand = type(catalogue_of(c)[0])("x", "user", p, Setup("u", 356.0 + e, 0.0, 490.0),
                                                 Mount("m", 65.0, R_C), 100.0)
                ok, why = fits(cand)
                lines.append(f"{name} {p} e{e} R_C{R_C}: {ok} {why} {clock.run_minutes(_AsRun(cand))!r}")
for p in PATTERNS:  # standalone programs
    (out / f"alone-{p}.nc").write_text(api.ncgen(p, R_B_mm=356.3945, start=(-390.0, 0.0, -112.2605), feed=2000.0))
(out / "planning.txt").write_text("\n".join(lines) + "\n")
print(len(lines), len(list(out.glob("*.nc"))))
