"""Ctrl-C during a solve is an interrupt, never a result.

CasADi checks for a pending SIGINT in its own C++ code as well as in latentoc's callbacks; when
it finds one there, it clears it and reports the solver status ``NonIpopt_Exception_Thrown``
with whatever point it had (a cost of 0, a "gain" of 100 %). :func:`watching` records every
SIGINT that arrives inside its block (and raises KeyboardInterrupt as Python's default handler
does), so that a block that returns normally after a swallowed SIGINT, or fails with another
error because of it (CasADi may turn it into a SystemError), raises KeyboardInterrupt at its end:
``latentoc.solve`` runs each kind's solver inside it.

The command line (:class:`CommandLine`) owns SIGINT from the first line of ``python -m latentoc``:
counted while its modules load, then the first one raises KeyboardInterrupt and later ones are
only counted, so that the unwinding and the message are never interrupted; a KeyboardInterrupt
lost inside a destructor is not printed and is raised again, and one a library caught on its way is
raised before the result is written (:func:`finish`) or when the command returns; from
:func:`finish` on Ctrl-C is ignored.
"""
from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from types import FrameType
from typing import Any

__all__ = ["watching", "deferred", "interrupts_seen", "defer_at_start", "CommandLine", "finish"]

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
            raise _interrupt() from exc
        raise
    finally:
        if install:
            signal.signal(signal.SIGINT, previous)
    if _seen > start:
        raise _interrupt()


def _interrupt() -> KeyboardInterrupt:
    """The KeyboardInterrupt a counted SIGINT becomes: the command line raises no second one."""
    global _armed
    _armed = False
    return KeyboardInterrupt()


def watching() -> AbstractContextManager[None]:
    """Run the block with SIGINT recorded (module doc); KeyboardInterrupt at its end if a SIGINT
    arrived and was swallowed inside it. Only in the main thread, and only where SIGINT has
    Python's default handler (an application's own handler is left alone)."""
    return _handled(_record, (signal.default_int_handler,))


def deferred() -> AbstractContextManager[None]:
    """Run the block with SIGINT counted but not raised (:func:`interrupts_seen` grows), so that no
    KeyboardInterrupt starts inside C code that calls back into Python (Ipopt's callbacks check the
    count and stop the solver instead); KeyboardInterrupt at the block's end if one arrived. Only in
    the main thread, and only over Python's default handler, :func:`watching`'s or the command line's."""
    return _handled(_count, (signal.default_int_handler, _record, _once))


_started: int | None = None  # SIGINTs seen when python -m latentoc started (defer_at_start)
_armed = False  # the command line's next SIGINT raises KeyboardInterrupt


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def defer_at_start() -> None:
    """The first line of ``python -m latentoc``: SIGINT counted, not raised, while the modules load
    (a KeyboardInterrupt inside an extension's import is printed by it or becomes another error);
    :class:`CommandLine` raises it once they have. Nothing where SIGINT is not Python's default
    (ignored by the parent, or an application's own handler)."""
    global _started
    if _main_thread() and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        _started = _seen
        signal.signal(signal.SIGINT, _count)


def _once(signum: int, frame: FrameType | None) -> None:
    """The command line's handler: KeyboardInterrupt once, then SIGINTs only counted."""
    global _seen, _armed
    _seen += 1
    if _armed:
        _armed = False
        raise KeyboardInterrupt


def _unraisable(hook: Callable[..., object]) -> Callable[..., object]:
    """sys.unraisablehook for the command line: a KeyboardInterrupt that a destructor swallowed (or
    an error it caused) is not printed, and is raised again in the main thread."""
    def quiet(args: Any) -> None:
        global _armed
        if isinstance(args.exc_value, KeyboardInterrupt):
            _armed = True
            import _thread

            _thread.interrupt_main()
        elif _seen <= _baseline:  # an error of its own, not one a SIGINT caused
            hook(args)
    return quiet


_baseline = 0  # SIGINTs seen when the current command line started


class CommandLine:
    """SIGINT for one run of the command line (module doc): :meth:`start` before the command,
    :meth:`interrupted` to tell an interrupt from an error, :meth:`end` after it."""

    def __init__(self) -> None:
        global _baseline
        self.baseline = _seen if _started is None else _started
        _baseline = self.baseline
        self.previous: Any = None
        self.hook = sys.unraisablehook

    def start(self) -> None:
        """Raise KeyboardInterrupt at the first SIGINT from now on (at once if one came while the
        modules loaded)."""
        global _armed
        if not _main_thread():
            return
        current = signal.getsignal(signal.SIGINT)
        if current is signal.default_int_handler or current is _count:
            self.previous = current
            _armed = True
            sys.unraisablehook = _unraisable(self.hook)
            signal.signal(signal.SIGINT, _once)
        if _seen > self.baseline:
            _armed = False
            raise KeyboardInterrupt

    def raise_swallowed(self) -> None:
        """KeyboardInterrupt if a SIGINT came while the command ran and the KeyboardInterrupt it raised
        was caught on its way (a library's bare ``except:``, say inside an import)."""
        if _seen > self.baseline:
            raise _interrupt()

    def interrupted(self, exc: BaseException) -> bool:
        """Whether ``exc`` ends the command because of Ctrl-C: a KeyboardInterrupt, or any error
        raised after a SIGINT (C code turns one into a SystemError, an import into an ImportError)."""
        return isinstance(exc, KeyboardInterrupt) or _seen > self.baseline

    def end(self) -> None:
        """SIGINT back to its handler before :meth:`start` (in ``python -m latentoc``: counted,
        until the process exits)."""
        global _armed
        _armed = False
        if self.previous is not None and _main_thread():
            signal.signal(signal.SIGINT, self.previous)
            if self.previous is not _count:
                sys.unraisablehook = self.hook


def finish() -> None:
    """The command's result is being written: from here Ctrl-C is ignored, so that a command is
    either interrupted with nothing written or ends with its result whole (command line only)."""
    global _armed
    if _main_thread() and signal.getsignal(signal.SIGINT) is _once:
        if _seen > _baseline:  # a SIGINT whose KeyboardInterrupt was caught on its way: nothing is written
            raise _interrupt()
        _armed = False
        signal.signal(signal.SIGINT, signal.SIG_IGN)
