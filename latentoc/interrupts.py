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
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from types import FrameType
from typing import Any

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
def _handled(handler: Callable[[int, FrameType | None], None], over: tuple[Any, ...]) -> Iterator[None]:
    """Run the block with SIGINT sent to ``handler`` (in the main thread, where the current handler
    is one of ``over``); KeyboardInterrupt at its end if a SIGINT arrived, also when the block fails
    because of it (inside C code: CasADi turns it into a SystemError)."""
    main = threading.current_thread() is threading.main_thread()
    previous = signal.getsignal(signal.SIGINT) if main else None
    install = any(previous is h for h in over)
    start = _seen
    if install:
        signal.signal(signal.SIGINT, handler)
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


def watching() -> AbstractContextManager[None]:
    """Run the block with SIGINT recorded (module doc); KeyboardInterrupt at its end if a SIGINT
    arrived and was swallowed inside it. Only in the main thread, and only where SIGINT has
    Python's default handler (an application's own handler is left alone)."""
    return _handled(_record, (signal.default_int_handler,))


def deferred() -> AbstractContextManager[None]:
    """Run the block with SIGINT counted but not raised (:func:`interrupts_seen` grows), so that no
    KeyboardInterrupt starts inside C code that calls back into Python (Ipopt's callbacks check the
    count and stop the solver instead); KeyboardInterrupt at the block's end if one arrived. Only in
    the main thread, and only over Python's default handler or :func:`watching`'s."""
    return _handled(_count, (signal.default_int_handler, _record))
