"""A problem as declared: what to optimise, never how.

* :mod:`.declaration` - :class:`~latentoc.problem.declaration.Problem`, a kind's settings resolved;
* :mod:`.schema` - the typed keys each kind declares once (type, range, default, meaning);
* :mod:`.kinds` - what a kind provides (``Kind``), what its solve returns (``Solution``) and the
  registry of kinds (``KINDS``);
* :mod:`.toml_files` - problem files in ``problems/`` by name or path, and problems as data;
* :mod:`.toml_limits` - the bounds checked on a file before the TOML parser reads it;
* :mod:`.sizes` - the sizes a problem may ask for, from the memory they take.
"""
