"""Write the demo campaigns of the built-in machine types into the package (mtmcal_bayes/datasets/machines/).

Each template here (``<type>.toml``) gives the set-ups, mounts, runs, probe and R-test positions of a demo campaign,
with zeros for the measurements, and its ``[truth]``; this script simulates the measurements from that truth through
the machine's chain with the instruments' scatter (seed 1) and saves ``<type>-demo.toml``.  Run from the project
root: ``python examples/machines/make_demo_campaigns.py [TYPE ...]`` (default: every template).  Name the types to
remake: the trunnion's, the vertical turn-mill's and the head-head's demos carry a truth re-expressed on the
computed default selection (bench/simulate_truths/) and are not simulated again from their templates.
"""

import sys
from pathlib import Path

import mtmcal_bayes as mb

HERE = Path("examples/machines")  # relative: the campaigns name their source
OUT = Path(mb.__file__).parent / "datasets" / "machines"

wanted = set(sys.argv[1:])
templates = sorted(HERE.glob("*.toml"))
unknown = wanted - {t.stem for t in templates}
if unknown:
    sys.exit(f"no template for {', '.join(sorted(unknown))} in {HERE}")
for template in templates:
    if wanted and template.stem not in wanted:
        continue
    campaign = mb.load_campaign(template)
    sim = mb.simulate(campaign, truth=campaign.truth, model="chain", noise=True, seed=1,
                      output=OUT / f"{template.stem}-demo.toml")
    print(sim.to_text())
