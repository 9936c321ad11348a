"""Reproduce thesis Table 4.5 and see where Table 5.3 does not reproduce.

Run:  python examples/identify_thesis.py
"""

import numpy as np

import mtmcal_bayes as mb

campaign = mb.load_campaign()  # the built-in thesis campaign (INTEGREX i-200)
print(mb.identify(campaign).to_text())

# The linear forward model: a batch of parameter vectors -> predicted eccentricities.
model = mb.LinearModel(campaign)
rng = np.random.default_rng(0)
theta = rng.normal(size=(5, len(model.space))) * model.space.display_scale() * 20  # ±20″ / ±20 µm
pred_um = model.predict(theta) * 1e3
print("\nPredicted eccentricities (µm) for 5 random parameter vectors:")
for label, col in zip(model.observations.labels, pred_um.T):
    print(f"  {label:16s}", " ".join(f"{v:8.2f}" for v in col))
