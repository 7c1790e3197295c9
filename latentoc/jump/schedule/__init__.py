"""When and along what the jump moves: :mod:`.phases` (stance, flight, landing, the contact schedule,
the knots at its events and the NLP's nodes and samples) and :mod:`.path` (the spline a method solves
along)."""
