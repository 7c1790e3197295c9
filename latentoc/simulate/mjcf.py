"""MJCF of a Pinocchio model for MuJoCo, with sphere contacts on a floor, and the state maps.

The kinematic tree, joint placements, axes, masses, COMs and inertias are Pinocchio's (inertia
written with ``fullinertia``). A chain of 1-DOF joints whose inner joints carry no mass and have one
child each (the ASF skeletons: ``lfemur_rz -> lfemur_ry -> lfemur_rx``) becomes one MJCF body that
holds the chain's hinges: MuJoCo applies a body's joints in order, each about its anchor and axis in
the frame the previous ones moved, so joint k takes the anchor and axis of the placement product
``S_k = P_2 ... P_k`` and the body frame is the chain's last joint frame times ``S_n^-1``.
A massless joint that cannot be merged (no child, several children, a contact frame on it, the
free-flyer root) gets :data:`NEGLIGIBLE_MASS` and an XML comment naming it: MuJoCo rejects moving
bodies without mass.

Contacts: each (frame, offset) point is a sphere of ``radius`` centred on the point, and the floor
plane lies at ``z = -radius``, so a sphere touches the floor when its point is at ``z = 0`` (the
plan's ground) whatever the foot's orientation. Only spheres and floor collide (spheres contype 1,
conaffinity 0; floor contype 0, conaffinity 1). Contact model: :data:`SOLREF` (time constant 2 ms,
critically damped: four 0.5 ms steps; MuJoCo needs at least two) and :data:`SOLIMP` (impedance 0.95
to 0.99 over 1 mm of penetration), the elliptic (Coulomb) friction cone, condim 3, the Newton solver
and the ``implicitfast`` integrator (the replay's joint damping is integrated implicitly).

Conventions (:func:`state_to_mujoco`): Pinocchio's free flyer q = [x y z qx qy qz qw], v[:6] =
(linear, angular), both in the base frame; MuJoCo's freejoint qpos = [x y z qw qx qy qz], qvel =
(linear in the world frame, angular in the base frame). The hinges are written depth first in
Pinocchio's joint order (:func:`dof_order`).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from xml.sax.saxutils import quoteattr

import numpy as np
import pinocchio as pin

from latentoc.errors import SimulationError

__all__ = ["mjcf_from_model", "state_to_mujoco", "state_from_mujoco", "force_from_mujoco", "dof_order",
           "joint_axis", "floating_base", "base_rotations", "SOLREF", "SOLIMP", "NEGLIGIBLE_MASS"]

SOLREF = (0.002, 1.0)  # contact time constant (s) and damping ratio
SOLIMP = (0.95, 0.99, 0.001, 0.5, 2.0)  # impedance dmin, dmax, width (m), midpoint, power
NEGLIGIBLE_MASS = 1e-6  # kg (and 1e-12 kg m^2 of inertia) for a massless body that cannot be merged
_AXES = {"RX": (1.0, 0.0, 0.0), "RY": (0.0, 1.0, 0.0), "RZ": (0.0, 0.0, 1.0)}
_ONE_DOF = {"JointModel" + k for k in _AXES} | {"JointModelRevoluteUnaligned"}


@dataclass
class _Body:
    """One MJCF body: Pinocchio joints ``joints`` (a chain), ``chain`` their placement products S_k."""

    joints: list[int]
    chain: list[pin.SE3]
    children: list[_Body] = field(default_factory=list)

    @property
    def offset(self) -> pin.SE3:
        """The last joint's frame in this body's frame (S_n)."""
        return self.chain[-1]


def joint_axis(model: pin.Model, j: int) -> np.ndarray:
    """The unit axis of revolute joint ``j`` in its own frame (a SimulationError for other joints)."""
    kind = model.joints[j].shortname()
    if kind not in _ONE_DOF:
        raise SimulationError(f"model {model.name!r}: joint {model.names[j]!r} is a {kind}; the MJCF export takes a "
                              "free-flyer root and 1-DOF revolute joints")
    if kind == "JointModelRevoluteUnaligned":
        return np.asarray(model.joints[j].extract().axis, dtype=float)
    return np.array(_AXES[kind[len("JointModel"):]])


def floating_base(model: pin.Model) -> bool:
    """Whether the root joint is a free flyer."""
    return model.njoints > 1 and model.joints[1].shortname() == "JointModelFreeFlyer"


def _massless(model: pin.Model, j: int) -> bool:
    Y = model.inertias[j]
    return Y.mass <= 0.0 and not np.any(Y.inertia)


def _bodies(model: pin.Model, keep: set[int]) -> list[_Body]:
    """The MJCF bodies under the world, merging massless chains (module doc); ``keep``: joints
    that must end their body (they carry a contact frame)."""
    children: dict[int, list[int]] = {j: [] for j in range(model.njoints)}
    for j in range(1, model.njoints):
        children[model.parents[j]].append(j)
    floating = floating_base(model)

    def build(j: int) -> _Body:
        body = _Body([j], [pin.SE3.Identity()])
        while (not (floating and body.joints[-1] == 1) and _massless(model, body.joints[-1])
               and len(children[body.joints[-1]]) == 1 and body.joints[-1] not in keep):
            c = children[body.joints[-1]][0]
            body.joints.append(c)
            body.chain.append(body.chain[-1] * model.jointPlacements[c])
        body.children = [build(c) for c in children[body.joints[-1]]]
        return body

    return [build(j) for j in children[0]]


def _walk(bodies: list[_Body]) -> list[_Body]:
    out: list[_Body] = []
    for b in bodies:
        out.append(b)
        out.extend(_walk(b.children))
    return out


def dof_order(model: pin.Model) -> np.ndarray:
    """Pinocchio's 1-DOF joint ids in the order of the MJCF's hinges (depth first)."""
    ids = [j for b in _walk(_bodies(model, set())) for j in b.joints]
    return np.array([j for j in ids if not (floating_base(model) and j == 1)], dtype=int)


def _num(x: object) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(np.asarray(x, dtype=float)))


def _quat(R: np.ndarray) -> str:
    c = pin.Quaternion(np.asarray(R)).coeffs()  # x y z w
    return _num([c[3], c[0], c[1], c[2]])


def _inertial(model: pin.Model, body: _Body, notes: list[str]) -> str:
    j = body.joints[-1]
    Y, S = model.inertias[j], body.offset
    if _massless(model, j):
        notes.append(model.names[j])
        return (f'<inertial pos="0 0 0" mass="{NEGLIGIBLE_MASS!r}" '
                f'diaginertia="{_num([NEGLIGIBLE_MASS * 1e-6] * 3)}"/>')
    I = S.rotation @ Y.inertia @ S.rotation.T
    full = [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]]
    return f'<inertial pos="{_num(S.act(Y.lever))}" mass="{Y.mass!r}" fullinertia="{_num(full)}"/>'


def mjcf_from_model(model: pin.Model, contacts: list[tuple[str, np.ndarray]], friction: float,
                    radius: float = 0.005, timestep: float = 0.0005) -> str:
    """The MJCF XML of ``model`` with a contact sphere per (frame, offset) point (module doc)."""
    if not (friction >= 0 and radius > 0 and timestep > 0):
        raise SimulationError(f"friction must be >= 0, radius and timestep > 0; got {friction}, {radius}, {timestep}")
    floating = floating_base(model)
    if floating and not model.jointPlacements[1].isIdentity():
        raise SimulationError(f"model {model.name!r}: the free-flyer root must be placed at the world origin")
    spheres: dict[int, list[tuple[int, str, np.ndarray]]] = {}
    for k, (name, offset) in enumerate(contacts):
        if not model.existFrame(name):
            raise SimulationError(f"model {model.name!r} has no frame {name!r} for a contact point")
        frame = model.frames[model.getFrameId(name)]
        if frame.parentJoint == 0:
            raise SimulationError(f"contact frame {name!r} is fixed to the world")
        point = frame.placement.act(np.asarray(offset, dtype=float).reshape(3))
        spheres.setdefault(frame.parentJoint, []).append((k, name, point))
    bodies = _bodies(model, set(spheres))
    contact = f'solref="{_num(SOLREF)}" solimp="{_num(SOLIMP)}" friction="{friction!r} 0.005 0.0001" condim="3"'
    notes: list[str] = []
    lines: list[str] = []

    def write(body: _Body, parent: pin.SE3, depth: int) -> None:
        pad = "  " * depth
        first = body.joints[0]
        place = parent * model.jointPlacements[first]
        lines.append(f'{pad}<body name={quoteattr(model.names[body.joints[-1]])} pos="{_num(place.translation)}" '
                     f'quat="{_quat(place.rotation)}">')
        if floating and first == 1:
            lines.append(f'{pad}  <freejoint name={quoteattr(model.names[1])}/>')
        else:
            for j, S in zip(body.joints, body.chain):
                lines.append(f'{pad}  <joint name={quoteattr(model.names[j])} type="hinge" '
                             f'pos="{_num(S.translation)}" axis="{_num(S.rotation @ joint_axis(model, j))}"/>')
        lines.append(f"{pad}  {_inertial(model, body, notes)}")
        for k, name, point in spheres.get(body.joints[-1], []):
            lines.append(f'{pad}  <geom name={quoteattr(f"contact{k}_{name}")} type="sphere" size="{radius!r}" '
                         f'pos="{_num(body.offset.act(point))}" contype="1" conaffinity="0" {contact}/>')
        for child in body.children:
            write(child, body.offset, depth + 1)
        lines.append(f"{pad}</body>")

    for b in bodies:
        write(b, pin.SE3.Identity(), 2)
    hinges = [j for b in _walk(bodies) for j in b.joints if not (floating and j == 1)]
    motors = [f'    <motor name={quoteattr(model.names[j])} joint={quoteattr(model.names[j])} gear="1" '
              'ctrllimited="false"/>' for j in hinges]
    comment = [f"  <!-- massless, unmergeable: {', '.join(notes)} get {NEGLIGIBLE_MASS} kg -->"] if notes else []
    return "\n".join([
        f"<mujoco model={quoteattr(model.name or 'model')}>",
        *comment,
        '  <compiler angle="radian" inertiafromgeom="false" autolimits="true" balanceinertia="false"/>',
        f'  <option timestep="{timestep!r}" gravity="{_num(model.gravity.linear)}" integrator="implicitfast" '
        'cone="elliptic" solver="Newton"/>',
        "  <worldbody>",
        f'    <geom name="floor" type="plane" size="0 0 1" pos="0 0 {-radius!r}" contype="0" conaffinity="1" {contact}/>',
        *lines,
        "  </worldbody>",
        "  <actuator>", *motors, "  </actuator>",
        "</mujoco>", ""])


def base_rotations(q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rotation matrices (n, 3, 3) and MuJoCo quaternions (n, 4: w x y z) of the free-flyer rows ``q``."""
    x, y, z, w = (q[:, 3 + k] for k in range(4))
    n = np.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    R = np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w),
                  2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w),
                  2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)], axis=-1)
    return R.reshape(-1, 3, 3), np.stack([w, x, y, z], axis=-1)


def _columns(model: pin.Model) -> tuple[np.ndarray, np.ndarray]:
    """Pinocchio's q and v columns of the hinges, in MJCF order."""
    order = dof_order(model)
    return (np.array([model.idx_qs[int(j)] for j in order], dtype=int),
            np.array([model.idx_vs[int(j)] for j in order], dtype=int))


def state_to_mujoco(model: pin.Model, q: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """MuJoCo's (qpos, qvel) of Pinocchio's (q, v); one state or rows of states (module doc)."""
    q2, v2 = np.atleast_2d(np.asarray(q, dtype=float)), np.atleast_2d(np.asarray(v, dtype=float))
    iq, iv = _columns(model)
    if floating_base(model):
        R, wxyz = base_rotations(q2)
        qpos = np.column_stack([q2[:, :3], wxyz, q2[:, iq]])
        qvel = np.column_stack([np.einsum("nij,nj->ni", R, v2[:, :3]), v2[:, 3:6], v2[:, iv]])
    else:
        qpos, qvel = q2[:, iq], v2[:, iv]
    return (qpos[0], qvel[0]) if np.ndim(q) == 1 else (qpos, qvel)


def state_from_mujoco(model: pin.Model, qpos: np.ndarray, qvel: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pinocchio's (q, v) of MuJoCo's (qpos, qvel): the inverse of :func:`state_to_mujoco`."""
    p2, w2 = np.atleast_2d(np.asarray(qpos, dtype=float)), np.atleast_2d(np.asarray(qvel, dtype=float))
    iq, iv = _columns(model)
    q, v = np.zeros((len(p2), model.nq)), np.zeros((len(p2), model.nv))
    if floating_base(model):
        q[:, :3], q[:, 3:6], q[:, 6] = p2[:, :3], p2[:, 4:7], p2[:, 3]
        q[:, 3:7] /= np.linalg.norm(q[:, 3:7], axis=1, keepdims=True)
        R, _ = base_rotations(q)
        v[:, :3], v[:, 3:6] = np.einsum("nji,nj->ni", R, w2[:, :3]), w2[:, 3:6]
        q[:, iq], v[:, iv] = p2[:, 7:], w2[:, 6:]
    else:
        q[:, iq], v[:, iv] = p2, w2
    return (q[0], v[0]) if np.ndim(qpos) == 1 else (q, v)


def force_from_mujoco(model: pin.Model, q: np.ndarray, qfrc: np.ndarray) -> np.ndarray:
    """Pinocchio's generalized force (nv) of MuJoCo's ``qfrc`` at Pinocchio configuration ``q``
    (the dual of the velocity map: the base force turned into the base frame)."""
    iq, iv = _columns(model)
    tau = np.zeros(model.nv)
    qfrc = np.asarray(qfrc, dtype=float)
    if floating_base(model):
        R, _ = base_rotations(np.atleast_2d(np.asarray(q, dtype=float)))
        tau[:3], tau[3:6], tau[iv] = R[0].T @ qfrc[:3], qfrc[3:6], qfrc[6:]
    else:
        tau[iv] = qfrc
    return tau
