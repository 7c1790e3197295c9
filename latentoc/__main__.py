"""``python -m latentoc``: see :mod:`latentoc.cli`."""

from .cli import main

raise SystemExit(main())
