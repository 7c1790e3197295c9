"""``python -m latentoc`` and the ``latentoc`` script (:func:`run`): see :mod:`latentoc.cli.parser`."""
from latentoc.runtime.interrupts import defer_at_start

defer_at_start()  # before any other import: a Ctrl-C from here on ends in "latentoc: interrupted"

import os  # noqa: E402
import signal  # noqa: E402
import sys  # noqa: E402

from latentoc.cli.parser import main  # noqa: E402


def run() -> None:
    """Run the command line and exit with its code."""
    code = main()
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the command is over: a late Ctrl-C does not end Python's exit
    if code == 130:  # interrupted: exit now, as a KeyboardInterrupt that passed through an extension's
        for stream in (sys.stdout, sys.stderr):  # init would make Python's exit kill the process by SIGINT
            try:
                stream.flush()
            except OSError:
                pass
        os._exit(130)
    raise SystemExit(code)


if __name__ == "__main__":
    run()
