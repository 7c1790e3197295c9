"""The command line, ``python -m latentoc COMMAND ...``.

* :mod:`.parser` - the commands' arguments, and :func:`~latentoc.cli.parser.main`, which runs one
  (the exit codes, Ctrl-C, input errors);
* :mod:`.commands` - each command's implementation, ``cmd_<name>(args)``;
* :mod:`.learn` - ``learn``: a GPDM learned from the user's motion file, and reading it back
  (``solve --gpdm``).
"""
