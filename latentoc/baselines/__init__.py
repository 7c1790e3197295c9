"""Baselines the latent optimisation is compared with (paper Sect. 4.1.2).

:mod:`latentoc.baselines.sampling`: kinodynamic RRT* on OMPL for the arm (Table 3); it needs the
optional extra ``pip install latentoc[sampling]``.
"""
