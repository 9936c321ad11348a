# %% [markdown]
# # A first fleet: three simulated machines, one overview
#
# Writes a small plant of simulated machines, runs `mtmcal-bayes fleet` on it and prints where to look:
#
# * **M-1**: beta_CZ steps by 40″ between its 2nd and 3rd campaign (a crash): the history flags it, dated.
# * **M-2**: alpha_XB drifts by 8″ a year (wear), measured in a workshop between 18 and 24 °C, alpha_XB moving by
#   1.5″/°C: the history separates the drift from the temperature and says when to recalibrate.
# * **M-3**: one campaign only, and a broken file beside it: reported, the rest completes.
#
# All three are of one type, so the fleet also pools what their histories taught about σ_model.
#
#     python examples/fleet_demo.py [FOLDER]
#
# FOLDER (default: a new temporary folder) receives `plant/` (the campaign files) and `fleet/` (the overview:
# open `fleet/index.html`). About half a minute on two cores (exact posteriors of the linear model). The same
# as shell commands: docs/fleet.md, "A first fleet".

# %%
import sys
import tempfile
from pathlib import Path

import mtmcal_bayes as mb

root = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tempfile.mkdtemp(prefix="mtmcal-fleet-demo-"))
plant = root / "plant"
tolerances = Path(__file__).resolve().with_name("plant_tolerances.toml")

# %% [markdown]
# ## The plant: each machine a series of campaigns simulated from the built-in thesis campaign

# %%
machines = {
    "M-1": dict(steps=["beta_CZ=40@3"], seed=1),
    "M-2": dict(ramps=["alpha_XB=8@1"], temperatures=[18.5, 23.0, 19.5, 24.0], thermal=["alpha_XB=1.5"], seed=2),
    "M-3": dict(n=1, seed=3),
}
for serial, how in machines.items():
    how = {"n": 4, "every_days": 91, **how}
    series = mb.simulate_history(truth=None, serial=serial, output=plant / serial, machine_type="INTEGREX i-200",
                                 **how)
    print(f"{serial}: {len(series)} campaign(s) in {plant / serial}")
(plant / "M-3" / "broken.toml").write_text('format = "mtmcal-campaign/1"\n[machine]\nserial = "M-3"\n')

# %% [markdown]
# ## The fleet: every campaign's posterior and every machine's history, in parallel on Dask

# %%
result = mb.fleet(plant, output=root / "fleet", sampler="exact", tolerances=tolerances, workers=2, cache=False)
for m in result.machines:
    flags = [f"{c['quantity']} changed before {c['date']}" for c in m["changes"]]
    due = [f"{f['quantity']} by {f['recalibrate_by']}" for f in m["forecast"] if f["recalibrate_by"]]
    print(f"{m['id']}: {'; '.join(flags) or 'no change flagged'}; recalibrate {', '.join(due) or 'beyond the horizon'}")
for e in result.errors:
    print(f"reported, the rest completed: {e['message']}")
for name, t in result.types.items():
    print(f"σ_model of type {name!r} from {t['histories']} histories: median {t['median_um']:.2f} µm "
          f"(prior file {t['prior_file']})")
print(f"\nopen {root / 'fleet' / 'index.html'}")
