"""The jumping robot and its feet: :mod:`.robot_declaration` (a problem file's ``[robot]``),
:mod:`.sagittal_base`, :mod:`.feet` (contact points and forces), :mod:`.zmp`,
:mod:`.support_polygon` (Eq. 35-36), :mod:`.torque_limits` (Eq. 34) and :mod:`.jump_robot` (what
the row families know of the robot)."""
