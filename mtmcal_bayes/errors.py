"""Errors a user can act on.

Every problem with user input is raised as a :class:`MtmcalError` whose string
is one line saying what is wrong and where: :class:`InputError` names the file
and the key, :class:`ParameterError` the function parameter.  The command line
prints that line on stderr and exits with status 2, never a traceback.
"""

from __future__ import annotations


class MtmcalError(Exception):
    """Base of all user-facing errors: ``str(err)`` is the one line to show."""


class InputError(MtmcalError):
    """A problem in an input file, located by ``source`` (file) and ``key``.

    ``key`` is a dotted TOML key (``"ballbar.runs[2].ex_um"``), a line
    (``"line 12"``) or ``None`` for the file as a whole.
    """

    def __init__(self, source: str, key: str | None, message: str):
        self.source, self.key, self.message = str(source), key, message
        where = f"{self.source}: {key}" if key else self.source
        super().__init__(f"{where}: {message}")


class ParameterError(MtmcalError):
    """A bad value of a function parameter, named as the Python API names it (``max_steps``).

    ``str(err)`` is ``"max_steps: <message>"``; the command line shows its own
    flag instead (``--max-steps: <message>``).  ``message`` must make sense after
    either, so it never names a flag itself.
    """

    def __init__(self, parameter: str, message: str):
        self.parameter, self.message = parameter, message
        super().__init__(f"{parameter}: {message}")
