"""``sample --data rtest`` on an R-test campaign of each built-in type, whole process, as a ratio to the import floor
(issue 43: ≤ 1.3 t_ref).

    python bench/rtest_speed.py [--repeats 5]

The campaigns are written into a temporary directory: each type's one-sphere static runs in all four settings of
frame and zero (tests/rtest_campaigns.py: :func:`every_setting_text`: 16 runs, 80 positions, one sphere, one nest),
their readings simulated (the chain, 0.5 µm scatter) from a truth drawn from the prior (seeded).
``t_ref`` is the import floor, ``python -c "import arviz, emcee, scipy.stats, numpy"``; each command runs as a fresh
process alternating with the floor (as bench/machines.py does) and its median wall time is divided by the floor's
median.  Prints one JSON document.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from types import SimpleNamespace

import numpy as np

sys.path.insert(0, str(Path(__file__).parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from targets import ratio_row, timed_against_floor  # noqa: E402  (fresh processes, each after the import floor)

from mtmcal_bayes.inference.log_posterior import LogPosterior  # noqa: E402
from mtmcal_bayes.io.campaign_reader import parse_campaign  # noqa: E402
from mtmcal_bayes.io.campaign_writer import save_campaign  # noqa: E402
from mtmcal_bayes.simulation.simulate import synthetic_campaign, truth_from_vector  # noqa: E402
from tests.rtest_campaigns import every_setting_text  # noqa: E402

TYPES = ("integrex-i200", "vertical-turn-mill", "trunnion", "head-head")
GOAL = 1.3


def write_campaign(machine: str, path: Path, seed: int = 1) -> None:
    """The R-test campaign of ``machine`` with readings simulated from a truth drawn from the prior, at ``path``."""
    c = parse_campaign(every_setting_text(machine))
    post = LogPosterior(c, "linear", data="rtest")
    theta = post.priors.rvs(1, np.random.default_rng(seed))[0]
    keep = [i for i, p in enumerate(post.space.parameters) if p.group in ("deviation", "rtest")]  # not the scale
    truth = truth_from_vector(SimpleNamespace(parameters=[post.space.parameters[i] for i in keep]), theta[keep])
    save_campaign(synthetic_campaign(c, truth, "chain", noise=True, seed=seed), path)


def ratios(repeats: int) -> dict:
    out: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        cwd = Path(tmp)
        for t in TYPES:
            write_campaign(t, cwd / f"{t}-rtest.toml")
        commands = {t: ["mtmcal-bayes", "sample", f"{t}-rtest.toml", "--data", "rtest", "--quiet"] for t in TYPES}
        t_ref, times = timed_against_floor(commands, cwd, repeats)
        out["t_ref_s"] = t_ref
        for t, med in times.items():
            out[f"sample --data rtest {t}"] = ratio_row(med, t_ref, GOAL)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    print(json.dumps(ratios(ap.parse_args().repeats), indent=1))


if __name__ == "__main__":
    main()
