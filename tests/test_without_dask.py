"""A command that uses no Dask runs without importing it, and writes the same results."""

import json
import subprocess
import sys
import textwrap

import arviz  # noqa: F401 - xarray imported in this process, as in any caller's

from mtmcal_bayes.without_dask import hide_dask

SCRIPT = textwrap.dedent("""
    import atexit, json, sys
    sys.argv = ["mtmcal-bayes", *json.loads(sys.argv[1])]

    def modules_at_exit():  # the command ends the process itself (cli._exit_now), after the exit handlers
        loaded = sorted(m for m in sys.modules if m.split(".")[0] in ("dask", "distributed"))
        print(json.dumps({"dask": loaded, "xarray": "xarray" in sys.modules}), file=sys.stderr)

    atexit.register(modules_at_exit)
    from mtmcal_bayes.cli import main
    sys.exit(main())
""")


def _command(args, cwd):
    done = subprocess.run([sys.executable, "-c", SCRIPT, json.dumps(args)], cwd=cwd, capture_output=True, text=True,
                          timeout=300)
    return done.stdout, {"status": done.returncode, **json.loads(done.stderr.strip().splitlines()[-1])}


def test_sample_imports_no_dask_and_writes_a_readable_posterior(tmp_path):
    out, seen = _command(["sample", "--sampler", "exact", "--seed", "3", "--json", "-o", "post.nc"], tmp_path)
    assert seen == {"status": 0, "dask": [], "xarray": True}
    result = json.loads(out)
    idata = arviz.from_netcdf(tmp_path / "post.nc")
    mean = result["summary"]["alpha_XB"]["mean"]  # printed to 10 significant digits
    assert abs(float(idata.posterior["alpha_XB"].mean()) - mean) <= 1e-9 * abs(mean)


def test_a_caller_with_xarray_loaded_is_left_alone():
    before = list(sys.meta_path)
    assert hide_dask("test") is False
    assert sys.meta_path == before
