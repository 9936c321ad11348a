"""The engine's one touch-probe model (``models/probe.py``): its kernels agree with each other, and a reading fitted
through DPRNT points is observed in its covariance frame on every built-in type."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import mtmcal_bayes as mb
from mtmcal_bayes import api
from mtmcal_bayes.inference.analytic import gaussian_posterior
from mtmcal_bayes.inference.log_posterior import LogPosterior
from mtmcal_bayes.io.campaign_writer import campaign_to_dict, save_campaign
from mtmcal_bayes.io.dprnt import read_dprnt
from mtmcal_bayes.io.tomlio import dumps
from mtmcal_bayes.models import make_model
from mtmcal_bayes.models.jacobian import jacobian_at_zero
from mtmcal_bayes.models.probe import ChainProbeKernel, ProbeModel
from mtmcal_bayes.simulation.simulate import truth_vector
from mtmcal_bayes.sphere import fit_sphere

TYPES = ("trunnion", "vertical-turn-mill", "head-head")


def test_the_chain_kernel_reads_the_thesis_probe_as_its_own_kernel_does(thesis):
    """The thesis' probe positions through the engine's chain kernel and through the thesis' kernel (``htm-literal``,
    Eq 2.10 with its lever arms and the exact affine inverse: an independent implementation) give the same readings
    for random deviations, stylus and sphere terms, to rounding, once the chain's commands are read as the thesis
    reads them: the programmed tool point, the command plus R(B)·(0, 0, −R_B) (written here from Eq 2.10's B rotation,
    not from the package).  Each run's datum is a free offset in the thesis' frame, so differences between its
    positions are compared."""
    literal = make_model("htm-literal", thesis, data="probe")
    chain = ProbeModel(thesis, literal.space, kernel=ChainProbeKernel(thesis.machine.description),
                       layout=literal.layout)
    space, L = literal.space, literal.layout
    # the chain has no pre-travel term rS (a described stylus has none): every other term is drawn
    drawn = [i for i, p in enumerate(space.parameters) if p.group == "deviation" or p.base in ("xS", "yS", "dRS", "xP", "yP")]
    rng = np.random.default_rng(11)
    theta = np.zeros((6, len(space)))
    theta[:, drawn] = rng.normal(size=(6, len(drawn))) * space.display_scale()[drawn] * 30  # ~30 µm, 30″
    B = np.radians([k.angle_deg if k.run == "b_axis" else 0.0 for k in literal.observations.keys[::3]])
    tool_point = np.stack([-np.sin(B), np.zeros_like(B), -np.cos(B)], axis=-1) * L.length[:, None]
    a = literal.readings(theta)
    b = chain.readings(theta) + tool_point
    moved = 0.0
    for run in ("c_axis", "b_axis"):
        at = L.run == run
        d = a[:, at] - b[:, at]
        np.testing.assert_allclose(d - d[:, :1], 0.0, atol=1e-9)
        rel = a[:, at] - literal.readings(np.zeros(len(space)))[:, at]
        moved = max(moved, np.abs(rel - rel[:, :1]).max())
    assert moved > 1e-2  # the drawn terms move the readings by tens of µm: the agreement is not of zeros


def _sphere_points(centre: np.ndarray, rng, radius: float = 12.5, noise_mm: float = 2e-3) -> np.ndarray:
    """Probed points (n, 3) of a sphere's upper half around ``centre`` (one side: an anisotropic fit covariance)."""
    polar, azimuth = np.meshgrid(np.radians([0.0, 30.0, 55.0, 80.0]), np.radians(np.arange(0.0, 360.0, 60.0)))
    d = np.stack([np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)], -1).reshape(-1, 3)
    d = np.unique(np.round(d, 12), axis=0)
    return centre + radius * d + rng.normal(0.0, noise_mm, size=d.shape)


@pytest.mark.parametrize("machine", TYPES)
def test_a_probe_run_read_from_dprnt_files_is_observed_in_its_fit_frame(machine, tmp_path):
    """A ``[[probe.runs]]`` run given as one DPRNT file per position (points simulated around the chain's readings
    at the demo's truth, 2 µm scatter): each centre is fitted, its observations are taken along the principal axes
    of its fit covariance plus the repeatability² (their variances its eigenvalues), the model turns its prediction
    and its Jacobian into the same frame, the truth explains the readings while zero does not (χ² of the fitted
    readings below its 0.999 quantile at the truth, above it at zero), the closed-form posterior follows, and
    saving keeps the files."""
    c = api.campaign_of(api.demo_campaign(machine))
    plain = make_model("chain", c, data="probe")
    theta = truth_vector(plain.space, c.truth.probe_part())
    sl = plain.layout.slices[0]
    run = c.probe.runs[0]
    rng = np.random.default_rng(3)
    points = [_sphere_points(x, rng) for x in plain.centres(theta)[sl]]
    files = []
    for i, pts in enumerate(points):
        f = tmp_path / f"p{i + 1}.txt"
        f.write_text("%\n" + "".join(f"X{x:.5f} Y{y:.5f} Z{z:.5f}\n" for x, y, z in pts))
        files.append(str(f))
    run.dprnt, run.centre_cov = files, np.zeros((1, run.positions, 3, 3))  # written as files; read back below
    save_campaign(c, tmp_path / "dprnt.toml")
    read = mb.load_campaign(tmp_path / "dprnt.toml")
    got = read.probe.runs[0]
    fits = [fit_sphere(read_dprnt(f).xyz) for f in files]  # the points as written, to 5 decimals
    assert got.centre_cov.shape == (1, run.positions, 3, 3)
    np.testing.assert_allclose(got.centres[0], [f.centre for f in fits], rtol=0, atol=1e-12)

    model = make_model("chain", read, data="probe")
    obs = model.observations
    rows = np.arange(3 * sl.start, 3 * sl.stop)
    assert [obs.keys[i].component for i in rows[:3]] == ["u1", "u2", "u3"]
    assert {k.component for i, k in enumerate(obs.keys) if i not in rows} <= {"X", "Y", "Z"}
    u2 = read.probe.repeatability ** 2
    lam, Q = np.linalg.eigh(np.array([f.centre_cov for f in fits]) + u2 * np.eye(3))  # (a, 3), (a, 3, 3)
    np.testing.assert_allclose(obs.base_var[rows], lam.reshape(-1), rtol=1e-9)
    y = np.einsum("kji,kj->ki", Q, got.centres[0] - plain.layout.nominal[sl])
    np.testing.assert_allclose(obs.mean[rows], y.reshape(-1), rtol=0, atol=1e-12)
    # the prediction and the Jacobian in the same frame as the data
    turned = lambda v: np.einsum("kji,nkj->nki", Q, v.reshape(len(v), -1, 3)[:, sl]).reshape(len(v), -1)  # noqa: E731
    np.testing.assert_allclose(model.predict(theta[None])[:, rows], turned(plain.predict(theta[None])), atol=1e-12)
    J, J0 = jacobian_at_zero(model), jacobian_at_zero(plain)
    np.testing.assert_allclose(J[rows].T, turned(J0.T), atol=1e-9 * np.abs(J0).max())
    np.testing.assert_allclose(np.delete(J, rows, axis=0), np.delete(J0, rows, axis=0), rtol=0, atol=0)
    chi2 = lambda th: np.sum((obs.mean[rows] - model.predict(th)[rows]) ** 2 / obs.base_var[rows])  # noqa: E731
    limit = stats.chi2.ppf(0.999, len(rows))
    assert chi2(theta) < limit < chi2(np.zeros_like(theta))
    g = gaussian_posterior(LogPosterior(read, "linear", data="probe"), 0.0)
    assert np.all(np.isfinite(g.sd)) and np.all(g.sd > 0)
    text = dumps(campaign_to_dict(read, tmp_path / "out"))
    assert '"../p1.txt"' in text
    assert ("centres_mm" in text) == (len(read.probe.runs) > 1)  # any other run keeps its centres


BAD_DPRNT = [
    ('dprnt = ["p1.txt", "p2.txt"]', "probe.runs[0].dprnt", "2 files for 12 positions"),
    ('centres_mm = [[[0, 0, 0]]]\ndprnt = ["p1.txt"]', "probe.runs[0]", "give either centres_mm or dprnt, not both"),
    ("", "probe.runs[0]", "no readings: give centres_mm (repeats x positions x 3) or dprnt"),
]


@pytest.mark.parametrize("readings, key, words", BAD_DPRNT)
def test_bad_dprnt_readings_of_a_probe_run_are_one_line(tmp_path, run_cli, readings, key, words):
    """A ``[[probe.runs]]`` run's DPRNT readings that cannot be used: one line naming the file and the key, exit 2."""
    text = mb.datasets.builtin_text("machines/trunnion-demo.toml")
    lines = text.splitlines(keepends=True)
    at = next(i for i, line in enumerate(lines) if line.startswith("centres_mm = "))
    path = tmp_path / "c.toml"
    path.write_text("".join(lines[:at]) + (readings + "\n" if readings else "") + "".join(lines[at + 1:]),
                    encoding="utf-8")
    code, _, err = run_cli("sample", str(path), "--sampler", "exact", "--data", "probe")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert str(path) in err and key in err and words in err, err


def test_a_dprnt_file_with_too_few_points_names_its_position(tmp_path, run_cli):
    """A DPRNT file of four points (a sphere through them, but no covariance) is refused by its index."""
    text = mb.datasets.builtin_text("machines/trunnion-demo.toml")
    lines = text.splitlines(keepends=True)
    at = next(i for i, line in enumerate(lines) if line.startswith("centres_mm = "))
    pts = _sphere_points(np.array([0.0, 60.0, -220.0]), np.random.default_rng(1))
    for i in range(12):
        (tmp_path / f"p{i}.txt").write_text("".join(f"X{x:.4f} Y{y:.4f} Z{z:.4f}\n" for x, y, z in
                                                    (pts[:4] if i == 5 else pts)))
    files = ", ".join(f'"p{i}.txt"' for i in range(12))
    path = tmp_path / "c.toml"
    path.write_text("".join(lines[:at]) + f"dprnt = [{files}]\n" + "".join(lines[at + 1:]), encoding="utf-8")
    code, _, err = run_cli("sample", str(path), "--sampler", "exact", "--data", "probe")
    assert code == 2 and len(err.strip().splitlines()) == 1, err
    assert "probe.runs[0].dprnt[5]" in err and "at least 5" in err, err
