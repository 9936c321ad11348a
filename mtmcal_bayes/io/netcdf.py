"""Posteriors on disk: ArviZ InferenceData as NetCDF, written atomically and read with one-line errors."""

from __future__ import annotations

from ..arviz_import import az
from ..errors import InputError
from .textfiles import atomic_output


def write_netcdf_atomic(idata, path) -> None:
    """Save an InferenceData as NetCDF through a temporary file (nothing half-written), uncompressed: posterior draws
    are random doubles, which zlib shrinks by 4 % for half again the writing time."""
    with atomic_output(path) as tmp:
        idata.to_netcdf(tmp, compress=False)


def read_posterior(path):
    """The ``posterior`` group of an InferenceData NetCDF file (``sample -o``); an unreadable file is an
    :class:`InputError` naming it."""
    try:
        return az.from_netcdf(path).posterior
    except Exception as exc:  # noqa: BLE001 - any unreadable file is one line for the user
        raise InputError(str(path), None, f"cannot read as an ArviZ posterior NetCDF: {exc}") from None


def read_posterior_attrs(path) -> dict:
    """The attributes of the ``posterior`` group of a posterior NetCDF file (model, data, ...; ``sample -o``),
    without reading its draws (milliseconds, where :func:`read_posterior` reads every group); an unreadable file is
    an :class:`InputError` naming it."""
    try:
        import h5netcdf

        with h5netcdf.File(path, "r") as f:
            return dict(f["posterior"].attrs)
    except Exception:  # noqa: BLE001 - not HDF5 as h5netcdf reads it: the general reader decides
        return dict(read_posterior(path).attrs)
