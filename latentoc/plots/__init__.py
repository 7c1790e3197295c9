"""Figures of latentoc results (Kang & Park 2015, Fig. 1, 3, 4, 5, 7), by what they draw.

Every ``plot_*`` function returns a :class:`matplotlib.figure.Figure` and accepts ``axes=``
(:mod:`.figure`); :func:`save` writes one as PNG, PDF or SVG; :func:`plot_solution` writes the
whole set of a result folder from its files alone (``python -m latentoc plot RESULT``).

* :mod:`.latent`: the latent path in its variance tube (equal axes)
* :mod:`.joints`: joint angles, velocities and torques with their limits
* :mod:`.stick`: stick frames with their times and a scale
* :mod:`.forces`: the jump's contact forces, cones, centre of pressure, ZMP and COM margins
* :mod:`.contact_points`: the feet's contact points by name, frame and offset (shared with the 3-D view)
* :mod:`.convergence`: Ipopt's per-iteration history
* :mod:`.studies`: gain against tube size, new start poses
* :mod:`.kinematics`: the stick figure's bones (shared with the animation and the 3-D view)
* :mod:`.animation`: the motion as a GIF, and the live 3-D view (meshcat or viser)
"""
from latentoc.plots.forces import (contact_series, plot_contact_forces, plot_contact_margins, plot_zmp_com, polygon_margin,
                                    support_vertices)
from latentoc.plots.convergence import plot_convergence
from latentoc.plots.contact_points import ContactPoints, contact_points_of, point_positions, world_forces
from latentoc.plots.figure import DPI, FIGSIZES, FORMATS, LIMIT_STYLE, pixel_size, save
from latentoc.plots.joints import plot_joint_curves, plot_torques, plot_velocities
from latentoc.plots.kinematics import (PLANES, SIDE_COLOURS, bones, floating_base, frame_indices, joint_positions, model_of, side,
                                       skeleton_segments)
from latentoc.plots.latent import plot_latent_tube, resample, tube_mesh
from latentoc.plots.solution import actuated_joints, plot_solution, solution_figures
from latentoc.plots.stick import plot_stick_frames, scale_bar_length
from latentoc.plots.studies import plot_gain_vs_tube, plot_start_poses

__all__ = [
    "DPI", "FIGSIZES", "FORMATS", "LIMIT_STYLE", "pixel_size", "save", "tube_mesh", "resample", "plot_latent_tube",
    "plot_joint_curves", "plot_velocities", "plot_torques", "plot_stick_frames", "scale_bar_length",
    "contact_series", "polygon_margin", "support_vertices", "ContactPoints", "contact_points_of", "point_positions",
    "world_forces", "plot_contact_forces", "plot_contact_margins", "plot_zmp_com",
    "plot_convergence", "plot_gain_vs_tube", "plot_start_poses", "plot_solution", "solution_figures",
    "actuated_joints", "PLANES", "SIDE_COLOURS", "bones", "side", "floating_base", "frame_indices",
    "joint_positions", "model_of", "skeleton_segments",
]
