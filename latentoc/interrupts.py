"""Ctrl-C during a solve is an interrupt, never a result.

CasADi checks for a pending SIGINT in its own C++ code as well as in latentoc's callbacks; when
it finds one there, it clears it and reports the solver status ``NonIpopt_Exception_Thrown``
with whatever point it had (a cost of 0, a "gain" of 100 %). :func:`watching` records every
SIGINT that arrives inside its block (and raises KeyboardInterrupt as Python's default handler
does), so that a block that returns normally after a swallowed SIGINT, or fails with another
error because of it (CasADi may turn it into a SystemError), raises KeyboardInterrupt at its end:
``latentoc.solve`` runs each kind's solver inside it.
"""
from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

__all__ = ["watching", "deferred", "interrupts_seen"]

_seen = 0  # SIGINTs received by the handler of this module


def interrupts_seen() -> int:
    """How many SIGINTs the handler of :func:`watching` has received in this process."""
    return _seen


def _record(signum: int, frame: FrameType | None) -> None:
    global _seen
    _seen += 1
    raise KeyboardInterrupt


def _count(signum: int, frame: FrameType | None) -> None:
    global _seen
    _seen += 1


@contextmanager
def watching() -> Iterator[None]:
    """Run the block with SIGINT recorded (module doc); KeyboardInterrupt at its end if a SIGINT
    arrived and was swallowed inside it. Only in the main thread, and only where SIGINT has
    Python's default handler (an application's own handler is left alone)."""
    main = threading.current_thread() is threading.main_thread()
    previous = signal.getsignal(signal.SIGINT) if main else None
    install = previous is signal.default_int_handler
    start = _seen
    if install:
        signal.signal(signal.SIGINT, _record)
    try:
        yield
    except Exception as exc:  # an error a SIGINT caused inside C code (CasADi: a SystemError)
        if _seen > start:
            raise KeyboardInterrupt from exc
        raise
    finally:
        if install:
            signal.signal(signal.SIGINT, previous)
    if _seen > start:
        raise KeyboardInterrupt


@contextmanager
def deferred() -> Iterator[None]:
    """Run the block with SIGINT counted but not raised (:func:`interrupts_seen` grows), so that no
    KeyboardInterrupt starts inside C code that calls back into Python (Ipopt's callbacks check the
    count and stop the solver instead); KeyboardInterrupt at the block's end if one arrived. Only in
    the main thread, and only over Python's default handler or :func:`watching`'s."""
    main = threading.current_thread() is threading.main_thread()
    previous = signal.getsignal(signal.SIGINT) if main else None
    install = previous is signal.default_int_handler or previous is _record
    start = _seen
    if install:
        signal.signal(signal.SIGINT, _count)
    try:
        yield
    except Exception as exc:
        if _seen > start:
            raise KeyboardInterrupt from exc
        raise
    finally:
        if install:
            signal.signal(signal.SIGINT, previous)
    if _seen > start:
        raise KeyboardInterrupt
