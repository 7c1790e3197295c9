"""The paper's experiments and the repository's committed outputs, remade by commands.

* :mod:`.paper` - Tables 2, 3, 4 and 6 and Fig. 5 rerun (``python -m latentoc reproduce``);
* :mod:`.figures` - the README's figures (``python -m latentoc reproduce --figures``);
* :mod:`.notebooks` - the notebooks run in place (``python -m latentoc notebooks``);
* :mod:`.provenance` - what a committed output was made from, so a test can tell it is stale.
"""
