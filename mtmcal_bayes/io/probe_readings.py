"""A probe run's readings in any campaign format: the sphere centres given (``centres_mm``, repeats × positions ×
3), or one DPRNT file of probed points per position, each fitted by a sphere (one repeat, with the fit's centre
covariance: the probe model observes such a reading along its covariance's principal axes)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..datasets import data_path
from ..errors import InputError, MtmcalError
from ..sphere import fit_sphere
from .dprnt import read_dprnt
from .toml_reader import TomlReader, kind_of

#: fewest probed points of a sphere fit whose centre covariance the likelihood can use (4 fit it exactly)
MIN_DPRNT_POINTS = 5


def probe_readings(r: TomlReader, t: dict, path: str, n_positions: int, *, base_dir: Path | None,
                   position: str = "position"):
    """Sphere centres of a probe run: ``centres_mm`` (r, a, 3) mm, or ``dprnt``, one DPRNT file per position (names
    relative to ``base_dir``; without one, the package's data), each fitted.  Returns ``(centres, cov or None, files
    or None)``, ``cov`` (1, a, 3, 3) mm².  ``position``: what the messages call a position (the thesis' format: an
    angle)."""
    has_c, has_d = "centres_mm" in t, "dprnt" in t
    if has_c == has_d:
        r.fail(path, f"no readings: give centres_mm (repeats x {position}s x 3) or dprnt (one DPRNT file per {position})"
               if not has_c else "give either centres_mm or dprnt, not both")
    if has_c:
        return r.array(t, "centres_mm", path, (None, n_positions, 3)), None, None
    files = t["dprnt"]
    key = f"{path}.dprnt"
    if not isinstance(files, list) or not all(isinstance(f, str) for f in files):
        r.fail(key, f"expected an array of file names, got {kind_of(files)}")
    if len(files) != n_positions:
        r.fail(key, f"{len(files)} files for {n_positions} {position}s: give one DPRNT file per indexed position")
    centres, cov = np.empty((1, n_positions, 3)), np.empty((1, n_positions, 3, 3))
    for i, name in enumerate(files):
        fpath = (base_dir / name) if base_dir is not None else data_path(name)
        try:
            pts = read_dprnt(fpath).xyz
            if len(pts) < MIN_DPRNT_POINTS:
                raise MtmcalError(f"{len(pts)} probed points; a sphere fit with a covariance needs at least "
                                  f"{MIN_DPRNT_POINTS}")
            fit = fit_sphere(pts)
        except MtmcalError as err:
            r.fail(f"{key}[{i}]", str(err) if isinstance(err, InputError) else f"{name}: {err}")
        centres[0, i], cov[0, i] = fit.centre, fit.centre_cov
    return centres, cov, list(files)


__all__ = ["MIN_DPRNT_POINTS", "probe_readings"]
