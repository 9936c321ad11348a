"""Every measuring program ``ncgen`` and ``design`` write on the built-in types' demo campaigns and on the thesis
campaign, to a folder, to compare two trees byte for byte (the thesis machine's pattern programs over every option:
``bench/thesis_commands.py``).

    PYTHONPATH=TREE python bench/programs.py OUT [--design]      # then: diff -r OUT_A OUT_B

Per demo type: every ball-bar run (``--run N``), every probe run, every pattern at its default and with an arc, a
step, a held axis and a feed; with ``--design``, the programs ``design -o`` writes (thesis and demos, seed 1).
"""
import sys
from pathlib import Path

from mtmcal_bayes import api
from mtmcal_bayes.errors import MtmcalError
from mtmcal_bayes.io.machine_reader import BUILTIN_TYPES, demo_campaign
from mtmcal_bayes.machines.patterns import patterns_of

out = Path(sys.argv[1])
out.mkdir(parents=True, exist_ok=True)
written = 0


def write(name: str, **kw) -> None:
    global written
    try:
        text = api.ncgen(**kw)
    except MtmcalError as err:  # a refusal is an output too
        text = f"refused: {type(err).__name__}: {err}\n"
    (out / f"{name}.nc").write_text(text)
    written += 1


for t in (t for t in BUILTIN_TYPES if t != "integrex-i200"):
    path = demo_campaign(t)
    c = api.campaign_of(path)
    desc = c.machine.description
    for i in range(1, len(c.ballbar.runs) + len(c.ballbar.planned) + 1):
        write(f"{t}-run{i}", campaign=path, run=i)
        write(f"{t}-run{i}-step2-feed700", campaign=path, run=i, step_deg=2.0, feed=700.0)
    for j, run in enumerate(c.probe.runs if c.probe is not None else []):
        write(f"{t}-probe{j + 1}", campaign=path, probe=str(j + 1))
        write(f"{t}-probe-{run.id}-feed50", campaign=path, probe=run.id, feed=50.0)
    for p in patterns_of(desc):
        write(f"{t}-{p}", pattern=p, campaign=path)
        others = [a.letter for a in desc.rotary_axes if a.letter != p[0]]
        write(f"{t}-{p}-arc", pattern=p, campaign=path, arc_deg=(-10.0, 20.0), step_deg=2.5,
              hold_deg={others[0]: 10.0} if others else None, feed=900.0)
        write(f"{t}-{p}-step3", pattern=p, campaign=path, step_deg=3.0)
        for s in c.ballbar.setups:
            for m in c.ballbar.mounts:
                write(f"{t}-{p}-{s}-{m}", pattern=p, campaign=path, setup=s, mount=m)

if "--design" in sys.argv:
    for t in BUILTIN_TYPES:
        campaign = None if t == "integrex-i200" else demo_campaign(t)
        api.design(campaign, seed=1, output=out / f"design-{t}")
print(written)
