"""Ctrl-C while a cluster's results are collected (:func:`mtmcal_bayes.cluster.remembered_interrupt`)."""

import os
import signal
import sys
import time

import pytest

from mtmcal_bayes.cluster import remembered_interrupt


class _RaisesWhenDeleted:
    def __init__(self, exc):
        self.exc = exc

    def __del__(self):
        raise self.exc


def test_a_ctrl_c_swallowed_where_it_arrived_is_raised_by_check():
    """The interrupt raises where it arrives; if that code drops it (as Distributed's callbacks do), ``check``
    raises it again; without one, ``check`` passes."""
    before = signal.getsignal(signal.SIGINT)
    with remembered_interrupt() as interrupt:
        interrupt.check()
        try:
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(1.0)  # the signal arrives here (in the main thread, at the next bytecode)
            pytest.fail("the interrupt did not raise where it arrived")
        except KeyboardInterrupt:
            pass  # dropped, as a callback would
        with pytest.raises(KeyboardInterrupt):
            interrupt.check()
    assert signal.getsignal(signal.SIGINT) is before


def test_an_interrupt_dropped_in_a_finaliser_is_not_reported_but_other_errors_are(monkeypatch):
    """Within the context a KeyboardInterrupt that Python can only report as "ignored" is not passed to the
    unraisable hook (the run says "interrupted" once, when ``check`` raises); any other exception still is; the
    hook is restored afterwards."""
    reported = []
    monkeypatch.setattr(sys, "unraisablehook", lambda info: reported.append(info.exc_type))
    before = sys.unraisablehook
    with remembered_interrupt() as interrupt:
        _RaisesWhenDeleted(KeyboardInterrupt())
        _RaisesWhenDeleted(ValueError("a real error in a finaliser"))
    assert reported == [ValueError] and sys.unraisablehook is before
    interrupt.check()  # no SIGINT arrived: an exception object alone is not an interrupt
