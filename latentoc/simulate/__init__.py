"""An independent physics check of a result: its torques replayed in MuJoCo (``latentoc simulate``).

* :mod:`.mjcf`: the MJCF of a Pinocchio model, contact spheres on a floor, the state conventions;
* :mod:`.replay`: the replay with joint PD tracking and its summary (imports ``mujoco``, the
  ``sim`` extra: ``pip install -e '.[sim]'``);
* :mod:`.command`: the command, its contact points from ``trajectory.npz`` and its files.
"""
from latentoc.simulate.mjcf import mjcf_from_model, state_from_mujoco, state_to_mujoco

__all__ = ["mjcf_from_model", "state_to_mujoco", "state_from_mujoco"]
