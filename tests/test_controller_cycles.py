"""The controller cycles' measurement (Heidenhain KinematicsOpt, Siemens CYCLE996): a calibration sphere on the
table probed at indexed positions of both rotary axes, no ball bar, on the built-in trunnion and head-head types
(docs/_controller_cycles_section.md).

The campaigns (tests/data/controller_cycles/, written by make_campaigns.py there) list their deviations
(``<type>-calibrated.toml``): §19's set, those the computed default selection leaves out as the stylus' own length
or the sphere's placement included (SPEC §21: an explicit selection is accepted), so that what a calibrated stylus
determines can be stated.  Each axis at four indexed
positions with the other at 0 and at one tilted or turned pose, a 150 mm stylus, one reading per position with a
1 µm repeatability.  What they determine is computed from the Jacobian, with the stylus as each set-up's nuisance
term (the package's default) and with the stylus calibrated (its centring and length known, as the cycles use
it); the posterior is the exact (linear) one at σ_model = 0, so each reading's sd is the probe's 1 µm.

The sd bounds: 1 µm for a position, 2″ for an angle.  Twelve to sixteen readings of 1 µm on lever arms of 100 to
300 mm (1 µm over 100 mm is 2.06″) give 0.3–0.6 µm and 0.3–1.5″ (the run: trunnion E_Y0A 0.56 µm, E_X0C 0.45 µm,
E_B0A 1.35″, E_C0A 1.42″, E_B0C 1.31″; head-head E_Y0A 0.53 µm, E_A0C 0.44″, E_B0A 0.90″, E_B(0C1)A 1.51″,
E_Z(0C1)A 0.43 µm; the largest, 1.51″, is E_B(0C1)A, seen only on the stylus' own 150 mm).
"""

from pathlib import Path

import numpy as np
import pytest

import mtmcal_bayes as mb
from mtmcal_bayes.api import campaign_of
from mtmcal_bayes.inference.analytic import gaussian_posterior
from mtmcal_bayes.inference.identifiability import identifiability
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.models import jacobian
from mtmcal_bayes.inference.identifiability import CENTRED, campaign_identifiability

DATA = Path(__file__).parent / "data" / "controller_cycles"
#: a calibrated stylus: its centring across the spindle and its length known
STYLUS = ("xS", "yS", "zS", "dRS")
#: sd bounds of what the cycle determines at a 1 µm probe (module docstring)
BOUND = {"um": 1.0, "arcsec": 2.0}

#: type -> (stylus free: determined, combinations, undetermined; stylus known: the same)
EXPECTED = {
    "trunnion": (
        (("E_B0A", "E_C0A", "E_B0C"),
         ("E_A0C + E_A0A", "E_Y0C + 0.2424 µm/″·E_A0A"),
         ("E_Y0A", "E_Z0A", "E_X0C", "E_C0C")),
        (("E_Y0A", "E_Z0A", "E_B0A", "E_C0A", "E_X0C", "E_B0C"),
         ("E_A0C + E_A0A", "E_Y0C + 0.2424 µm/″·E_A0A"),
         ("E_C0C",)),
    ),
    "head-head": (
        (("E_A0C", "E_B0C", "E_Y0A", "E_B0A"),
         ("E_C0A + E_C0C",),
         ("E_X0C", "E_Y0C", "E_Z0A", "E_A0A", "E_Y(0C1)A", "E_B(0C1)A", "E_Z(0C1)A")),
        (("E_A0C", "E_B0C", "E_Y0A", "E_B0A", "E_B(0C1)A", "E_Z(0C1)A"),
         ("E_C0A + E_C0C", "E_Y(0C1)A + 1.454 µm/″·E_A0A"),
         ("E_X0C", "E_Y0C", "E_Z0A")),
    ),
}


@pytest.fixture(scope="module", params=sorted(EXPECTED))
def cycle(request):
    """``(type, campaign, log posterior at σ_model = 0, Jacobian)`` of one type's cycle campaign."""
    campaign = mb.load_campaign(DATA / f"{request.param}-cycle.toml")
    post = LogPosterior(campaign, "linear", data="probe", sigma_model=0.0)
    return request.param, campaign, post, jacobian(post.forward)


def _classes(ident):
    return ident.determined, tuple(c.name for c in ident.combinations), ident.undetermined


def _known_stylus(post):
    """The exact posterior with the stylus calibrated: its prior sds scaled to nothing."""
    scale = np.array([1e-9 if p.base in STYLUS else 1.0 for p in post.space.parameters])
    return gaussian_posterior(post, 0.0, prior_scale=scale)


def test_what_the_cycle_determines(cycle):
    """Exactly these deviations, combinations and undetermined ones, with the stylus free and calibrated."""
    kind, _, post, jac = cycle
    free, known = EXPECTED[kind]
    assert _classes(campaign_identifiability(post)) == free
    fixed = [b for b in CENTRED + STYLUS if any(p.base == b for p in post.space.parameters)]
    assert _classes(identifiability(jac, post.space, known=fixed)) == known


def test_posterior_sds_at_a_1um_probe(cycle):
    """Each determined deviation and combination below the bound (1 µm, 2″), its posterior mean within 4 sd of
    the truth the readings were simulated from; each undetermined one keeps most of its prior sd."""
    kind, campaign, post, jac = cycle
    space = post.space
    scale = space.display_scale()
    g = _known_stylus(post)
    fixed = [b for b in CENTRED + STYLUS if any(p.base == b for p in space.parameters)]
    ident = identifiability(jac, space, known=fixed)
    truth = campaign.truth.deviations
    unit = {p.name: p.unit for p in space.parameters}
    for name in ident.determined:
        i = space.names.index(name)
        sd, mean, true = g.sd[i] / scale[i], g.mean[i] / scale[i], truth[name] / scale[i]
        assert sd < BOUND[unit[name]], (kind, name, sd)
        assert abs(mean - true) < 4 * sd, (kind, name, mean, true, sd)
    for c in ident.combinations:
        weights = {n: w / scale[space.names.index(n)] for n, w in c.weights.items()}  # per internal unit
        mean, sd = g.linear_combination(weights)
        true = sum(w * truth[n] for n, w in weights.items())
        assert sd < BOUND[c.unit], (kind, c.name, sd)
        assert abs(mean - true) < 4 * sd, (kind, c.name, mean, true, sd)
    prior_sd = {q.name: q.sd for q in post.priors.priors}
    for name in ident.undetermined:
        i = space.names.index(name)
        assert g.sd[i] > 0.9 * prior_sd[name], (kind, name)


def test_a_free_stylus_is_confounded_with_the_axes_positions(cycle):
    """With the stylus at its tool-setter prior (10 µm) the positions it is confounded with keep about that sd:
    the trunnion's A line (Y, Z) and C line (X), the head-head spindle's offset along its axis."""
    kind, _, post, _ = cycle
    space = post.space
    g = gaussian_posterior(post, 0.0)
    confounded = {"trunnion": ("E_Y0A", "E_Z0A", "E_X0C"), "head-head": ("E_Z(0C1)A",)}[kind]
    for name in confounded:
        i = space.names.index(name)
        assert 9.0 < g.sd[i] / space.display_scale()[i] < 10.5, (kind, name)


def test_a_probe_only_campaign_is_measured_for_the_probe_data(run_cli):
    """A described machine's probe-only campaign is a measured one: ``sample`` takes its probe data by default;
    asked for the ball bar it says in one line that there are no ball-bar runs."""
    path = DATA / "trunnion-cycle.toml"
    assert campaign_of(path, measured=True).ballbar.runs == []
    code, out, err = run_cli("sample", str(path), "--sampler", "exact", "--json", "--quiet")
    assert code == 0 and '"data": "probe"' in out, err
    code, out, err = run_cli("sample", str(path), "--sampler", "exact", "--data", "ballbar")
    assert code == 2 and "--data" in err and "[[ballbar.runs]]" in err and len(err.strip().splitlines()) == 1, err
