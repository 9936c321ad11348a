"""The simultaneous band of a compensated program (docs/compensation.md): the error no block of the program exceeds
with 95 % probability — per posterior draw the largest residual over the blocks, the 95 % quantile of those maxima.

Its coverage over machines drawn from the priors is bench/compensation_described.py's; here its exact properties.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import units
from mtmcal_bayes.compensation.chain_kinematics import work_tool_point
from mtmcal_bayes.compensation.compensate import (
    compensate,
    program_commands,
    read,
    worst_block_p95,
)
from mtmcal_bayes.compensation.values import deviation_draws
from mtmcal_bayes.io.gcode import LINEAR
from mtmcal_bayes.io.machine_reader import demo_campaign
from mtmcal_bayes.machines import generated
from mtmcal_bayes.machines.chain import Chain

PROGRAM = Path(__file__).parents[1] / "examples" / "machines" / "head-head-five-axis.nc"


def test_worst_block_p95_is_the_quantile_of_the_per_draw_maxima():
    """On residuals with a known structure: one block, or every block the same, gives the pointwise quantile; a
    block shifted by a constant in every draw gives that block's quantile; independent blocks give more than any
    block's own quantile, and the share of draws whose worst block exceeds it is 5 %."""
    rng = np.random.default_rng(4)
    r = np.abs(rng.normal(size=(4000, 1)))
    assert worst_block_p95(r) == np.quantile(r[:, 0], 0.95)
    assert worst_block_p95(np.repeat(r, 7, axis=1)) == np.quantile(r[:, 0], 0.95)
    assert worst_block_p95(np.c_[r, r + 3.0]) == pytest.approx(np.quantile(r[:, 0], 0.95) + 3.0, abs=1e-12)
    many = np.abs(rng.normal(size=(4000, 30)))
    band = worst_block_p95(many)
    assert band > np.quantile(many, 0.95, axis=0).max()
    assert np.mean(many.max(axis=1) > band) == pytest.approx(0.05, abs=1 / 4000)


def test_the_simultaneous_band_of_a_compensation_recomputed_from_its_draws():
    """The head-head's demo (four deviations left at zero, so the two bands differ) with its 60-block program: the
    whole-program band equals the 95 % quantile of the per-draw largest residual, recomputed here from the posterior's
    draws through the description's chain; likewise the band of the part the data vouch for (those left at zero held
    at zero in the draws); each is at least the largest pointwise band and at most the largest residual of any draw;
    the JSON and the text state them."""
    c = mb.load_campaign(demo_campaign("head-head"))
    program = read(c, PROGRAM)
    posterior = mb.sample(c, sampler="exact", seed=1)
    result = compensate(c, program, posterior)
    draws, _, _ = deviation_draws(c, posterior)
    desc = c.machine.description
    chain, length = Chain(desc, generated(desc)), result.info["tool_length_mm"]
    q = program_commands(c, program)
    q_c = {**q, **dict(zip(LINEAR, result.xyz_c.T))}
    nominal = work_tool_point(chain, length, q, {})[0]
    n = len(next(iter(draws.values())))

    def residual(dev):  # (n, k) µm
        return units.from_internal(np.linalg.norm(work_tool_point(chain, length, q_c, dev, n=n) - nominal, axis=-1),
                                   "um")

    left = {d["name"] for d in result.info["not_measured"] if d["status"] == "left at zero"}
    assert left
    full, seen = residual(draws), residual({nm: v for nm, v in draws.items() if nm not in left})
    np.testing.assert_allclose(result.residual_p95_um, np.quantile(full, 0.95, axis=0), rtol=1e-9)
    determined = result.info["residual_determined_um"]
    for r, band in ((full, result.residual_program_p95_um), (seen, determined["program_p95"])):
        maxima = np.sort(r.max(axis=1))
        assert band == pytest.approx(np.quantile(maxima, 0.95), rel=1e-9)
        assert np.quantile(r, 0.95, axis=0).max() <= band <= maxima[-1]
    assert determined["program_p95"] > determined["p95_max"] * (1 + 1e-6)  # the blocks do not move as one here
    j = result.to_json()  # what --json prints
    assert j["residual_um"]["program_p95"] == result.residual_program_p95_um
    assert j["residual_determined_um"]["program_p95"] == determined["program_p95"]
    text = result.to_text()  # what compensate prints
    assert f"no block's error exceeds {result.residual_program_p95_um:.1f} µm" in text
    assert f"{determined['program_p95']:.1f} µm the whole program" in text
