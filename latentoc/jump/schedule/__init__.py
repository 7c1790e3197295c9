"""When and along what the jump moves: :mod:`.phases` (stance, flight, landing, the contact schedule
and the knots at its events) and :mod:`.path` (the spline a method solves along)."""
