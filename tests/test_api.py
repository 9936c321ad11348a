"""The Python API: one function per command, keyword-only beyond the first argument, each command's output
reproducible from it, errors that name parameters, one progress protocol."""

from __future__ import annotations

import importlib
import inspect
import io
import json
import pkgutil

import pytest

import mtmcal_bayes as mb
from mtmcal_bayes import api
from mtmcal_bayes.datasets import data_path
from mtmcal_bayes.io.json_text import json_text
from mtmcal_bayes.progress import ProgressEvent, StderrProgress

FIG_4_30A = data_path("fig4_30a_bx_original.nc")
DPRNT = data_path("fig5_13_dprnt_output.txt")
COMMAND_FUNCTIONS = ["identify", "probe_fit", "simulate", "sensitivity", "sample", "closed_form", "report", "plan",
                     "ncgen", "instruments", "compensate", "sbc", "history", "simulate_history", "fleet"]


@pytest.mark.parametrize("name", COMMAND_FUNCTIONS)
def test_api_functions_are_keyword_only_beyond_the_first_argument(name):
    params = list(inspect.signature(getattr(mb, name)).parameters.values())
    for module in pkgutil.walk_packages(mb.__path__, "mtmcal_bayes."):  # no subpackage may shadow a function
        importlib.import_module(module.name)
    assert getattr(mb, name) is getattr(api, name)
    assert params[0].kind is inspect.Parameter.POSITIONAL_OR_KEYWORD
    assert all(p.kind is inspect.Parameter.KEYWORD_ONLY for p in params[1:]), name
    assert getattr(mb, name).__doc__


def _cli_json(run_cli, *argv):
    code, out, err = run_cli(*argv, "--json")
    assert code == 0, err
    return json.loads(out)


def _api_json(result):
    return json.loads(json_text(result.to_json()))  # as the CLI prints it: rounded, NaN -> null


@pytest.mark.parametrize("argv,call", [
    (("identify",), lambda tmp: mb.identify()),
    (("probe-fit", str(DPRNT)), lambda tmp: mb.probe_fit(DPRNT)),
    (("sensitivity",), lambda tmp: mb.sensitivity()),
    (("instruments",), lambda tmp: mb.instruments()),
    (("sample", "--closed-form", "--sigma-model-um", "0.4"), lambda tmp: mb.closed_form(sigma_model_um=0.4)),
    (("simulate", "--truth", "{truth}"), lambda tmp: mb.simulate(truth=tmp / "truth.toml")),
    (("compensate", str(FIG_4_30A), "-o", "{out}", "--values", "ballbar"),
     lambda tmp: mb.compensate(FIG_4_30A, output=tmp / "out.nc", values="ballbar")),
])
def test_cli_output_is_reproducible_from_the_api(run_cli, tmp_path, argv, call):
    (tmp_path / "truth.toml").write_text("[deviations]\nbeta_XB_arcsec = -24\n")
    argv = [a.format(truth=tmp_path / "truth.toml", out=tmp_path / "out.nc") for a in argv]
    result = call(tmp_path)
    assert _cli_json(run_cli, *argv) == _api_json(result)
    code, out, _ = run_cli(*argv)
    assert code == 0 and out == result.to_text() + "\n"


def test_ncgen_text_is_the_api_text(run_cli):
    code, out, _ = run_cli("ncgen", "BX", "--x0", "-390", "--z0", "-112.2605", "--step-deg", "2.5", "--feed", "2000")
    assert code == 0 and out == mb.ncgen("BX", start=(-390.0, 0.0, -112.2605), feed=2000)


def test_seeded_sample_is_the_same_from_the_cli_and_the_api(run_cli):
    cli = _cli_json(run_cli, "sample", "--seed", "5", "--max-steps", "500", "--quiet")
    py = _api_json(mb.sample(seed=5, max_steps=500))
    for doc in (cli, py):  # timings are not results
        for key in ("wall_time_s", "ess_bulk_per_second"):
            doc["diagnostics"].pop(key)
    assert cli == py


def test_sbc_is_the_same_from_the_cli_and_the_api(run_cli, tmp_path):
    cli = _cli_json(run_cli, "validate", "sbc", "--sampler", "exact", "--n", "20", "--workers", "1", "--quiet")
    py = _api_json(mb.sbc(sampler="exact", n=20, workers=1))
    for doc in (cli, py):
        for key in ("wall_time_s", "replicate_seconds_median"):
            doc.pop(key)
    assert cli == py


def test_campaign_argument_takes_a_campaign_a_path_or_nothing(thesis, tmp_path):
    path = tmp_path / "c.toml"
    mb.save_campaign(thesis, path)
    values = [mb.identify(c).ballbar["beta_XB"].value for c in (None, thesis, path, str(path))]
    assert values[0] == pytest.approx(values[1]) == pytest.approx(values[2]) == pytest.approx(values[3])


@pytest.mark.parametrize("call,parameter", [
    (lambda: mb.sample(max_steps=10), "max_steps"),
    (lambda: mb.sample(model="quadratic"), "model"),
    (lambda: mb.plan(targets=["nope"]), "targets"),
    (lambda: mb.sbc(n=1), "n"),
    (lambda: mb.ncgen("BQ"), "pattern"),
    (lambda: mb.compensate(FIG_4_30A, model="linear"), "model"),
])
def test_api_errors_name_the_parameter_not_a_flag(call, parameter):
    with pytest.raises(mb.ParameterError) as info:
        call()
    assert info.value.parameter == parameter
    assert str(info.value).startswith(f"{parameter}: ") and "--" not in str(info.value)


def test_report_reuses_a_posterior_without_sampling_again(tmp_path, monkeypatch):
    """The given posterior is not sampled again; the thesis campaign's probe readings add only the probe-only
    and fused posteriors (the instruments' comparison)."""
    from mtmcal_bayes.reporting import build

    post = mb.sample(seed=3, max_steps=500)
    real = build.sample_posterior
    sampled = []

    def only_other_data(analysis, **k):  # the report hands each sampling its campaign's analysis, data included
        assert analysis.data != "ballbar", "sampled the given posterior again"
        sampled.append(analysis.data)
        return real(analysis, **k)

    monkeypatch.setattr(build, "sample_posterior", only_other_data)
    events = []
    rep = mb.report(output=tmp_path / "r", posterior=post, progress=events.append)
    assert rep.posterior is post and (tmp_path / "r" / "index.html").exists()
    assert sorted(sampled) == ["both", "probe"]
    assert any("drawing corner.png" in e.message for e in events)
    assert rep.to_json()["summary"] == post.to_json()["summary"]


def test_compensate_takes_a_posterior_object(thesis):
    post = mb.sample(seed=4, max_steps=500)
    from_object = mb.compensate(FIG_4_30A, posterior=post)
    assert from_object.info["uncertainty_from"] == "posterior draws from the given posterior"
    assert from_object.residual_p95_um.shape == (from_object.xyz.shape[0],)


def test_stderr_progress_prints_first_last_and_stages_and_throttles_the_rest():
    stream = io.StringIO()
    show = StderrProgress(stream, min_interval=3600.0)
    show(ProgressEvent("sampling [linear]", "step 500", 500, 2000))
    show(ProgressEvent("sampling [linear]", "step 1000", 1000, 2000))  # within the interval: dropped
    show(ProgressEvent("report", "drawing corner.png"))  # a stage: always
    show(ProgressEvent("sampling [linear]", "step 2000", 2000, 2000))  # the last: always
    assert stream.getvalue().splitlines() == ["sampling [linear]: step 500", "report: drawing corner.png",
                                              "sampling [linear]: step 2000"]
