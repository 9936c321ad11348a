"""How far the nonlinear kinematic model departs from the linear thesis relations at thesis magnitudes.

    python bench/nonlinearity.py [--draws 200]

Truth: thesis Table 4.5 (dx_BT = 0, dx_CZ = 53.13 µm), W-ball offsets of 60 µm in
random directions (thesis Sec 2.5.2: 10–60 µm). Prints, per eccentricity component,
the largest |htm-thesis − linear| over the draws, and the same without W offsets.
"""

import argparse

import numpy as np

from mtmcal_bayes import LinearModel, load_campaign, units
from mtmcal_bayes.plugins.thesis.kinematic import HTMModel


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--draws", type=int, default=200)
    args = ap.parse_args()
    c = load_campaign()
    lin, htm = LinearModel(c), HTMModel(c, "htm-thesis")
    sp = lin.space
    table45 = {"alpha_CZ": 1.10, "beta_CZ": -25.16, "alpha_XB": -20.89, "beta_XB": -24.11,
               "gamma_XB": 5.63, "alpha_BT": 9.63}
    base = sp.vector({k: v * units.ARCSEC for k, v in table45.items()})
    base[sp.index("dx_CZ")], base[sp.index("dy_CZ")] = 0.05313, -0.04563
    rng = np.random.default_rng(0)
    theta = np.tile(base, (args.draws, 1))
    for mount in c.ballbar.mounts:
        v = rng.normal(size=(args.draws, 3))
        v *= 0.060 / np.linalg.norm(v, axis=1, keepdims=True)
        for k, b in enumerate("xyz"):
            theta[:, sp.index(f"{b}W[{mount}]")] = v[:, k]
    d_w = np.abs(htm.predict(theta) - lin.predict(theta)).max(axis=0) * 1e3
    d_0 = np.abs(htm.predict(base) - lin.predict(base)) * 1e3
    print("max |htm-thesis − linear| (µm), Table 4.5 deviations")
    print(f"  {'component':16s} {'no W offset':>12s} {'W 60 µm':>10s}")
    for label, a, b in zip(lin.observations.labels, d_0, d_w):
        print(f"  {label:16s} {a:12.4f} {b:10.4f}")
    print(f"  overall max: {d_w.max():.4f} µm")


if __name__ == "__main__":
    main()
