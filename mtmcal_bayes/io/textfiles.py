"""Reading user text files with one-line errors, and writing files atomically (nothing half-written)."""

from __future__ import annotations

import codecs
import contextlib
import os
import shutil
import tempfile
from pathlib import Path

from ..errors import InputError, MtmcalError


def read_user_text(path: str | os.PathLike, kind: str) -> str:
    """Text of the file at ``path``; a missing, unreadable or binary file is an :class:`InputError`.

    ``kind`` names what the file should be (``"campaign file"``, ``"DPRNT file"``).  A leading UTF-8
    byte-order mark (Windows editors write one) is dropped: every text input is read through here.
    """
    p = Path(path)
    if not p.exists():
        raise InputError(str(p), None, "file not found")
    if p.is_dir():
        raise InputError(str(p), None, f"is a directory, not a {kind}")
    try:
        raw = p.read_bytes()
    except OSError as exc:
        raise InputError(str(p), None, f"cannot read as a {kind}: {exc.strerror or exc}") from None
    if raw.startswith(codecs.BOM_UTF8):  # stripped here, not by "utf-8-sig": exc.start below indexes raw
        raw = raw[len(codecs.BOM_UTF8):]
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:  # name the line of the first bad byte: binary, or saved as Latin-1/UTF-16
        line = raw.count(b"\n", 0, exc.start) + 1
        raise InputError(str(p), f"line {line}", f"not UTF-8 text (byte 0x{raw[exc.start]:02x}): "
                         f"cannot read as a {kind}; save it as UTF-8") from None


def check_writable(path: str | os.PathLike, what: str) -> None:
    """Fail early, before any work, when the directory ``path`` would be written into does not exist.

    ``what`` names the output (``"posterior"``, ``"compensated program"``).
    """
    parent = Path(path).resolve().parent
    if not parent.is_dir():
        raise MtmcalError(f"{path}: cannot write the {what}: directory {parent} does not exist")


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike):
    """Yield a temporary path beside ``path``; on success it replaces ``path``, on failure it is removed.

    Nothing is ever left half-written under ``path``.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    try:
        yield tmp
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; give the file the usual permissions
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_text_atomic(path: str | os.PathLike, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file, so nothing is left half-written."""
    with atomic_output(path) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")


def _umask() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return umask


@contextlib.contextmanager
def atomic_directory(path: str | os.PathLike):
    """Yield a temporary directory beside ``path``; on success its files move into ``path``.

    ``path`` is created if needed (its parent must exist); files already in it
    with other names are kept, files with the same names replaced, and a folder
    of the same name replaced whole (a design's ``programs/``, a fleet's
    ``machines/``: what an earlier run left there is not mixed with this one's).
    On failure the temporary directory is removed and ``path`` is untouched.
    """
    path = Path(path)
    tmp = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
    aside = []
    try:
        yield tmp
        os.chmod(tmp, 0o777 & ~_umask())  # mkdtemp creates 0700
        if not path.exists():
            os.replace(tmp, path)
            return
        for f in sorted(tmp.iterdir()):
            target = path / f.name
            if f.is_dir() and target.is_dir():  # a folder is not replaced by os.replace: the old one set aside
                aside.append(path / f".{f.name}-old-{os.getpid()}")
                os.replace(target, aside[-1])
            os.replace(f, target)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
        for old in aside:
            shutil.rmtree(old, ignore_errors=True)
