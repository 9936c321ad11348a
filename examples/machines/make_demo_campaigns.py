"""Write the demo campaigns of the built-in machine types into the package (mtmcal_bayes/datasets/machines/).

Each template here (``<type>.toml``) gives the set-ups, mounts, runs and probe positions of a demo campaign, with
zeros for the measurements, and its ``[truth]``; this script simulates the measurements from that truth through
the machine's chain with the instruments' scatter (seed 1) and saves ``<type>-demo.toml``.  Run from the project
root: ``python examples/machines/make_demo_campaigns.py``.
"""

from pathlib import Path

import mtmcal_bayes as mb

HERE = Path("examples/machines")  # relative: the campaigns name their source
OUT = Path(mb.__file__).parent / "datasets" / "machines"

for template in sorted(HERE.glob("*.toml")):
    campaign = mb.load_campaign(template)
    sim = mb.simulate(campaign, truth=campaign.truth, model="chain", noise=True, seed=1,
                      output=OUT / f"{template.stem}-demo.toml")
    print(sim.to_text())
