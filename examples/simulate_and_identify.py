"""Simulate the thesis campaign from a known truth with both kinematic models, then identify.

Shows (1) that the thesis formulas invert `htm-thesis` data to within second-order
effects, and (2) how far `htm-literal` data (Eq 2.10 as printed) lead them astray:
model-form uncertainty.

Run:  python examples/simulate_and_identify.py
"""

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.campaign import Truth
from mtmcal_bayes.simulation import synthetic_campaign

table_4_5 = {"alpha_CZ": 1.10, "beta_CZ": -25.16, "alpha_XB": -20.89, "beta_XB": -24.11,
             "gamma_XB": 5.63, "alpha_BT": 9.63}
truth = Truth(deviations={k: v * units.ARCSEC for k, v in table_4_5.items()})
truth.deviations["dx_CZ"] = units.to_internal(53.13, "um")
truth.deviations["dy_CZ"] = units.to_internal(-45.63, "um")
truth.mounts = {"C": {"xW": 0.040, "yW": -0.030}}  # W-ball clamping shift, mm

campaign = mb.load_campaign()
print(f"{'quantity':18s} {'truth':>9s} {'htm-thesis':>11s} {'htm-literal':>12s}")
results = {m: mb.identify_ballbar(synthetic_campaign(campaign, truth, m)) for m in ("htm-thesis", "htm-literal")}
for name in mb.IDENTIFIABLE:
    true = (truth.deviations.get("dx_CZ", 0) - truth.deviations.get("dx_BT", 0)) if name == "dx_CZ_minus_dx_BT" \
        else truth.deviations.get(name, 0.0)
    unit = results["htm-thesis"][name].unit
    print(f"{name:18s} {units.from_internal(true, unit):9.2f} "
          f"{results['htm-thesis'][name].display:11.2f} {results['htm-literal'][name].display:12.2f}  "
          f"{units.SYMBOL[unit]}")
