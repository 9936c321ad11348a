"""Posteriors on disk: ArviZ InferenceData as NetCDF, written atomically and read with one-line errors."""

from __future__ import annotations

from ..arviz_import import az
from ..errors import InputError
from .textfiles import atomic_output


def write_netcdf_atomic(idata, path) -> None:
    """Save an InferenceData as NetCDF through a temporary file (nothing half-written)."""
    with atomic_output(path) as tmp:
        idata.to_netcdf(tmp)


def read_posterior(path):
    """The ``posterior`` group of an InferenceData NetCDF file (``sample -o``); an unreadable file is an
    :class:`InputError` naming it."""
    try:
        return az.from_netcdf(path).posterior
    except Exception as exc:  # noqa: BLE001 - any unreadable file is one line for the user
        raise InputError(str(path), None, f"cannot read as an ArviZ posterior NetCDF: {exc}") from None
