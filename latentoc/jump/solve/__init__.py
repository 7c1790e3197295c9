"""Solving the jump: :mod:`.initial_point` (the training start), :mod:`.consistent_path` (its path
moved so that the planted foot's base is physical), :mod:`.exchange` (the rows the 1 kHz checks
add), :mod:`.warm` (a point carried into a larger NLP) and :mod:`.solve` (phase 1, phase 2, the
exchange's rounds)."""
