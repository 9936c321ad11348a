"""Errors a user can act on.

Every problem with user input is raised as a :class:`MtmcalError` whose string
is one line saying what is wrong and where: :class:`InputError` names the file
and the key, :class:`ParameterError` the function parameter.  The command line
prints that line on stderr and exits with status 2, never a traceback.

Errors cross process boundaries (the report's drawing and planning processes, Dask workers) by pickle.  Pickle
rebuilds an exception by calling its class with ``args`` — here the one formatted line, which the constructors of
:class:`InputError` and :class:`ParameterError` do not take — so every :class:`MtmcalError` pickles its state
instead and arrives as the error it was.  An unexpected exception in another process comes back as a
:class:`StepFailure` that names the step it stopped (``drawing corner.png``, ``replicate 17 of the calibration``).
"""

from __future__ import annotations


def _rebuilt(cls: type, args: tuple, state: dict) -> BaseException:
    """An exception of ``cls`` with ``args`` and attributes ``state``, made without calling its constructor."""
    exc = cls.__new__(cls, *args)
    exc.args = args
    exc.__dict__.update(state)
    return exc


class _PickledByState(Exception):
    """An exception pickled as its class, ``args`` and attributes, whatever its constructor takes."""

    def __reduce__(self):
        return _rebuilt, (type(self), self.args, dict(self.__dict__))


class MtmcalError(_PickledByState):
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


class StepFailure(_PickledByState):
    """An unexpected exception raised in another process, with the step it stopped.

    ``step`` says what the process was doing (``"drawing corner.png"``), ``kind`` and ``message`` are the
    exception's class name and text, ``trace`` its formatted traceback in that process (shown when debugging).
    Not an :class:`MtmcalError`: it is a fault of the package, not of the input.
    """

    def __init__(self, step: str, kind: str, message: str, trace: str = ""):
        self.step, self.kind, self.message, self.trace = step, kind, message, trace
        super().__init__(f"{step}: {kind}: {message}")

    @classmethod
    def of(cls, step: str, exc: BaseException) -> BaseException:
        """What to send back for ``exc`` raised during ``step``: the package's own errors (and an existing
        :class:`StepFailure`, which already names its step) as they are, anything else as a StepFailure."""
        if isinstance(exc, (MtmcalError, StepFailure)):
            return exc
        import traceback

        trace = "".join(traceback.format_exception(exc))
        return cls(step, type(exc).__name__, str(exc).splitlines()[0] if str(exc) else "", trace)
