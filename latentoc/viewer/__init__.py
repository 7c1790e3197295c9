"""The 3-D view of a result: one self-contained HTML page (``python -m latentoc view RESULT``).

The robot's own meshes where its URDF has them (example-robot-data robots, the user's URDF), capsules
along the skeleton otherwise; the optimised motion with the initial one as a translucent ghost; for a
contact motion the contact forces, friction cones, support polygon, COM and ZMP; play, pause, a time
slider and the speed. :mod:`.geometry` (the robot's parts), :mod:`.scene` (the data), :mod:`.html`
(the page; three.js embedded), ``js/page.js`` (the viewer).
"""
from latentoc.viewer.geometry import Part, part_poses, robot_parts
from latentoc.viewer.html import page_html, write_html
from latentoc.viewer.scene import build_scene

__all__ = ["write_html", "page_html", "build_scene", "robot_parts", "part_poses", "Part"]
