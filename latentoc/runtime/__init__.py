"""What every command runs on: where files are, how they are written, progress, threads, Ctrl-C.

* :mod:`.paths` - the data folders (``robots/``, ``problems/``) and the on-disk cache;
* :mod:`.files` - atomic files and folders, output checks, strict JSON, checksums;
* :mod:`.progress` - progress bars or lines, and ``--quiet``;
* :mod:`.threads` - OpenBLAS's thread count and the mapped blocks' threads;
* :mod:`.interrupts` - Ctrl-C during a solve is an interrupt, never a result;
* :mod:`.environment` - where a result was computed: versions, CPU, threads.
"""
