"""Simulation-based calibration with R-test data on every built-in type (docs/rtest.md, "Validation").

    python bench/rtest_sbc.py [--n 200] [--seed 1] [--workers 1] [--types TYPE ...]

Per type, the exact sampler (``validate sbc --sampler exact``), ``n`` replicates at ``seed``:

* ``rtest``: the R-test alone, on the one-sphere static runs in each of the four settings of frame and zero
  (tests/rtest_campaigns.py: :func:`every_setting_text`: 16 runs, one sphere, one nest);
* ``all``: every instrument, the type's demo campaign (the thesis campaign on the thesis type) with those runs
  added: the ball bar, the touch probe and the R-test (the nutating head's demo has R-test runs of its own: it as it
  is).

Prints per campaign the ranked quantities (what its Jacobian determines, then the discrepancy scales), each one's
p_uniform, 90 % coverage and verdict (the module's criterion: p > 0.01 and the coverage inside its 99 % binomial
range), and the seconds.  With Q quantities a calibrated posterior fails one now and then (each ≈ 2 %: a p below
0.01, or a coverage outside its 99 % range).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mtmcal_bayes.cluster import dask_client  # noqa: E402
from mtmcal_bayes.io.campaign_reader import parse_campaign  # noqa: E402
from mtmcal_bayes.validation import SBCSettings, run_sbc  # noqa: E402
from tests.rtest_campaigns import every_setting_text, with_every_instrument_text  # noqa: E402

TYPES = ("integrex-i200", "vertical-turn-mill", "trunnion", "head-head", "nutating-head")
CAMPAIGNS = {"rtest": every_setting_text, "all": with_every_instrument_text}


def print_table(title: str, r, seconds: float, seed: int) -> int:
    """Print one SBC run's table (per quantity p_uniform, 90 % coverage, z sd, verdict) under ``title``; the number of
    quantities failing the verdict."""
    s = r.summary()
    lo, hi = r.verdict_band()
    print(f"\n### {title}: N = {len(r.ranks)}, seed {seed}, {seconds:.1f} s, {len(r.quantities)} quantities, "
          f"90 % coverage band {lo:.3f}–{hi:.3f}, p > {r.p_threshold:.2g}\n")
    print("| quantity | p_uniform | coverage_90 | z_sd | ok |\n|---|---|---|---|---|")
    for q in r.quantities:
        row = s.loc[q]
        print(f"| {q} | {row['p_uniform']:.3f} | {row['coverage_90']:.3f} | {row['z_sd']:.3f} | "
              f"{'yes' if row['ok'] else 'NO'} |")
    return int((~s["ok"]).sum())


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--types", nargs="+", choices=TYPES, default=list(TYPES), help="the built-in types (default all)")
    args = ap.parse_args()
    failed = 0
    with dask_client(workers=args.workers) as client:
        address = client.scheduler.address
        for machine in args.types:
            for data, text in CAMPAIGNS.items():
                t0 = time.perf_counter()
                r = run_sbc(parse_campaign(text(machine)),
                            SBCSettings(n=args.n, sampler="exact", data=data, scheduler=address, seed=args.seed,
                                        workers=args.workers))
                failed += print_table(f"{machine}, --data {data}", r, time.perf_counter() - t0, args.seed)
    print(f"\nquantities failing: {failed}")


if __name__ == "__main__":
    main()
