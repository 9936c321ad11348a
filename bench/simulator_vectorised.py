"""Vectorised kinematic simulator against a per-draw loop of the same model, in one run.

    python bench/simulator_vectorised.py [--draws 10000] [--model htm-thesis]

Prints both wall times and their ratio; also checks the two give the same numbers.
"""

import argparse
import time

import numpy as np

from mtmcal_bayes import load_campaign
from mtmcal_bayes.models import make_model


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--draws", type=int, default=10_000)
    ap.add_argument("--model", default="htm-thesis")
    args = ap.parse_args()

    model = make_model(args.model, load_campaign())
    rng = np.random.default_rng(0)
    theta = rng.normal(size=(args.draws, len(model.space))) * model.space.display_scale() * 30  # ~30″ / 30 µm

    t0 = time.perf_counter()
    batch = model.predict(theta)
    t_vec = time.perf_counter() - t0

    t0 = time.perf_counter()
    loop = np.array([model.predict(th) for th in theta])
    t_loop = time.perf_counter() - t0

    assert np.allclose(batch, loop, rtol=0, atol=1e-12)
    runs = len(model.campaign.ballbar.runs)
    print(f"model {args.model}: {args.draws} parameter draws x {runs} runs -> {batch.shape} eccentricities")
    print(f"  vectorised (one call): {t_vec:8.3f} s")
    print(f"  per-draw loop        : {t_loop:8.3f} s")
    print(f"  ratio loop/vectorised: {t_loop / t_vec:8.1f}x")


if __name__ == "__main__":
    main()
