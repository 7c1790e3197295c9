"""The solved jump checked: :mod:`.export` (the motion on a 1 kHz grid) and :mod:`.verify` (its
recomputation with numeric Pinocchio)."""
