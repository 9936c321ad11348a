"""Simulation-based calibration of each built-in type's R-test demo campaign (docs/rtest.md, "The R-test demos").

    python bench/rtest_demo_sbc.py [--n 200] [--seed 1] [--workers 1]

Per type, the exact sampler (``validate sbc --sampler exact``), every instrument the demo has (the R-test), ``n``
replicates at ``seed``: the ranked quantities (what its Jacobian determines, then the discrepancy scale), each one's
p_uniform, 90 % coverage and verdict (the module's family-wise criterion, docs/validation.md), and the seconds.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mtmcal_bayes.cluster import dask_client  # noqa: E402
from mtmcal_bayes.io import load_campaign  # noqa: E402
from mtmcal_bayes.io.machine_reader import rtest_demo_campaign  # noqa: E402
from mtmcal_bayes.validation import SBCSettings, run_sbc  # noqa: E402
from bench.rtest_sbc import print_table  # noqa: E402

TYPES = ("integrex-i200", "vertical-turn-mill", "trunnion", "head-head")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=1)
    args = ap.parse_args()
    failed = 0
    with dask_client(workers=args.workers) as client:
        address = client.scheduler.address
        for machine in TYPES:
            t0 = time.perf_counter()
            r = run_sbc(load_campaign(rtest_demo_campaign(machine)),
                        SBCSettings(n=args.n, sampler="exact", data="all", scheduler=address, seed=args.seed,
                                    workers=args.workers))
            failed += print_table(f"{machine} R-test demo", r, time.perf_counter() - t0, args.seed)
    print(f"\nquantities failing: {failed}")


if __name__ == "__main__":
    main()
