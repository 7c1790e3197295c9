"""Problem kinds on the derivative layer (:mod:`latentoc.nlp`), one module per kind:
its NLP (families of robot blocks fed by a GP or identity layer) and its bounds.

* :mod:`.min_torque` - minimum-torque motion of a fixed-base robot (Eq. 22, 29).
"""
