"""What follows from the path by construction: :mod:`.planted_legs` (the planted foot: the legs'
dependent joints and, in contact, the base) and :mod:`.ballistic` (the flight's base, integrated)."""
