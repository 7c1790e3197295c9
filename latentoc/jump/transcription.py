"""The broad-jump NLP (Kang & Park 2015, Sect. 4.2, Eq. 33-36), solved by Ipopt.

Decision variables
------------------
* the free latent control points P[1:-1] of the B-spline x(t) (m = 21, d = 3; the end
  points stay on the training path, Sect. 4.2 "boundary conditions");
* the contact-phase base splines (variables ``phi_s`` in stance and ``phi_l`` in the landing):
  with ``base_model="spline"`` the base's own (x, z, pitch) B-splines (8 control points each),
  with ``"pinned"`` the foot pitch of the toe-pinned anchoring (:mod:`.contact`); and the
  landing toe position x_L;
* contact force generator weights (6 per contact node: heel, ball and toe on the two edges
  of their friction pyramid) and the touchdown impulse (6);
* the flight's takeoff state (COM, COM velocity, angular momentum) and its pitch at the
  flight nodes, tied to the stance and to the integrated pitch rate by equality rows.
* the time scale k (``JumpSettings.time_scale``, bounds 0.85-1.15): the motion runs in real
  time t = k s of the training's time s, so every phase lasts k times its training duration
  and the flight time is free.  Splines stay in s; real-time derivatives carry 1/k and
  1/k^2.  With the phase durations fixed (k = 1) the ballistic flight could not both leave
  the toe-pinned stance and meet the toe-pinned landing: Ipopt's restoration ended at a
  takeoff COM height mismatch of 2.3 cm, every other row satisfied (measured, issue 6).

Joint motion: y = mu_Q(x(t)) (GPDM mean, Eq. 18), y' and y'' by the chain rule
(Eq. 26-28); the right side is the mirror image.  Base in flight: ballistic (the paper's
forward "hybrid dynamics", integrated in closed form from the takeoff state, :mod:`.flight`).
Base in contact, two models:

* ``"spline"`` (the default): the base has its own smooth motion, and the feet stay on the
  ground through rows: the toe tip within ``foot_tolerance`` (1 cm) of its ground point (0, 0)
  in stance and (x_L, 0) in the landing, a loaded heel or ball within ``contact_tolerance`` of
  the ground.  The base rows of RNEA equal sum J^T f at every node, and the forces follow from
  the base's accelerations, as in the paper's simulation;
* ``"pinned"``: the toe tip is fixed exactly and the base follows from the leg joints by
  kinematics (:func:`anchored_function`), with the foot pitch free.  Every error of the learned
  leg joints then becomes a base acceleration: along the training fit the motion needs normal
  forces of -1.3 to 2.1 and horizontal forces of -2.6 to 3.7 body weights per foot, where the
  captured motion with its own (smoothed) base needs 0.07 to 1.23 and -0.01 to 0.32, and the GP
  mean's joints with a spline of the captured base 0.59 to 1.05 and -0.35 to 0.81 (measured,
  issue 6).  The 1 cm tolerance is of the size of the capture's own toe motion in stance
  (1.0 cm forward, -1.5 to +0.5 cm vertically).

The touchdown position of the flight must meet the landing's base.

Impact at touchdown: perfectly inelastic for the feet (restitution 0): the toe tip stops
(anchoring), the joints keep their (prescribed, continuous) velocities, and the base
velocity jumps by ``M_bb (v+ - v-) = (J^T Pi)_base`` with the ground impulse Pi built from
the same unilateral friction-pyramid generators as the forces (so Pi is unilateral and in
the cone).  The paper's restitution 0.5 belongs to its penalty-contact simulator; with
feet that must stay on the ground after landing, a bouncing contact would start a second
flight, which the fixed phase sequence excludes.

Constraints (hard): base rows (sagittal x, z, pitch; the lateral rows vanish by symmetry
and are checked in :mod:`.verify`), tube sigma^2 <= delta (Eq. 29), torque limits (Eq. 34),
contact-force cone/unilateral/CoP (by the generators), the contact schedule (a loaded heel
keeps the foot flat, a loaded ball stays on the ground, unloaded points carry no force;
:mod:`.phases`; ``contact_model="complementarity"`` keeps the earlier relaxed complementarity), no
ground penetration in flight, ZMP in the support polygon over the landing and the projected
COM in it once the landing has settled (Eq. 35, 36).
Objective (Eq. 33): maximise the jump distance x_L - x_0 between the toe tip's ground points
(the motion's own toe travel, within ``foot_tolerance`` of it, is ``verify``'s ``toe_displacement``).

Flight: ballistic, integrated from the takeoff state (:mod:`.flight`): the base rows hold at
every instant (1 kHz residual ~1e-13 body weights, against 0.3-0.5 with the collocated base
spline it replaced).  Contact phases: the base rows, cone, CoP, torque limits and
contact schedule hold at nodes every 10 ms (node counts 32/80/62; the flight's torque rows
every 5 ms), and the needed wrench's cone and centre of pressure, and the torques of the
joints no foot force enters, every ``wrench_spacing`` between them, just inside each unloaded
interval of the schedule and at every spline breakpoint (:func:`wrench_rows`); the point
forces act on their own bodies (heel and ball on the foot, toe tip on the toes), as in the
torque-limit estimate.  The exported motion is checked
on 1 kHz by :mod:`.verify`.

Derivatives (:mod:`.lifted`): every row block is a per-node SX Function of inputs affine in
the decision vector (contact node, flight node, takeoff, touchdown, pitch rate, tube),
compiled with its Jacobian to C; Ipopt gets jac_g = blockdiag(dF/du) M and an L-BFGS Hessian,
or with ``hessian="exact"`` the compiled node Hessians chained the same way
(:func:`.lifted.lifted_hessian`; the time scale's curvature and the pitch integral k A pd by the
product rule).  Compiled blocks are evaluated node by node on :func:`.lifted.threads` threads.

Measured history (issue 6; 2 shared cores; L-BFGS; tube 0.02 unless stated):

* takeoff at the feet's lift (0.350 s) and m = 11: with all hard constraints on, phase 1 ends
  infeasible.  Two causes, both measured: the toe tip leaves the ground at 0.308 s (now the
  takeoff, :mod:`.phases`), and an 11-point latent spline smooths the push-off, so the
  toe-pinned takeoff has 1.26 m/s of vertical velocity against the captured 1.84 (m = 15:
  1.64, m = 21: 1.96); simulated ballistically, that flight lands the toe 25 cm below the
  ground at touchdown, against 1.5 cm with m = 21;
* m = 21, toe-off takeoff, collocated flight spline, nodes 12/12/18, all constraints on:
  phase 1 and phase 2 both converge (192 + 255 iterations, 256 s), distance 0.661 m (training
  0.732 m).  The 1 kHz check then showed the flight residual (0.48 body weights, now removed by
  the ballistic flight) and, between contact nodes, a needed wrench whose centre of pressure
  leaves the foot (torque-limit excess up to 380 N m at the toe joint, fz < 0 at one sample):
  the node constraints need a denser grid or inter-node constraints;
* ballistic flight and the tube on a 5 ms grid (this version), nodes 12/12/18, all
  constraints on: phase 1 and 2 converge (192 + 105 iterations, constraint violation 2e-8),
  distance 0.503 m (training 0.732 m), 774 s wall / 724 s CPU; the constraint Jacobian takes
  2.25 s per evaluation (241 s of phase 2's time for 107 evaluations).  1 kHz check: flight
  base residual 5.5e-14 body weights, min normal force 30.6 N, max sigma^2 0.020095 for
  delta 0.02; between contact nodes the needed wrench still leaves the foot (friction ratio
  9.5, centre of pressure 10 m outside where fz is small, torque-limit excess 977 N m), so the
  contact phases need inter-node constraints before the jump counts as valid.
* lifted, compiled rows (this version), contact nodes every 10 ms (32/20/62), point forces on
  their own bodies, all constraints on, tube 0.02: constraint Jacobian 31 ms per evaluation
  (2.3 s before, with 12/12/18 nodes), constraints 7 ms, first build 35 s plus about 10 min of
  gcc once per machine, rebuild 0.9 s; a finite-difference check of the Jacobian agrees to
  1e-8 relative.  Phase 1 stops at 400 iterations (violation 0.019) and phase 2 reports
  Infeasible_Problem_Detected after 372 (violation 2.6e-3 in the complementarity rows),
  665 s wall, most of it inside Ipopt (2313 constraint evaluations in line searches and
  restoration), distance 0.21 m.  The training start needs unattainable wrenches at the
  dense nodes (non-negative least-squares base residual up to 20 body weights at touchdown,
  3-5 in the push-off): the toe-pinned base inherits the capture's foot-joint noise.  1 kHz
  check of that end point: friction ratio 0.36, min normal force 77 N, centre-of-pressure
  margin -0.12 m, torque-limit excess 5.9 N m (977 before), point-cone violation 0.09 body
  weights, flight residual 3e-14.
* this version: contact schedule instead of complementarity, free time scale, initial latent
  path smoothed with its takeoff and touchdown state kept, torque limits from the scheduled
  training fit with a 5 N m floor.  Phase 1 and phase 2 converge at every tube of the sweep
  (tube 0.02 from the training fit: 346 + 406 iterations, 94 s).  Each change was measured
  on its own: with complementarity rows Ipopt's dual infeasibility grew to 1e11; with fixed
  phase durations phase 1 ended locally infeasible at a 2.3 cm takeoff-height mismatch;
  without smoothing it ended locally infeasible (violation 0.014); with the plain 10 % margin
  the head's 1.9 N m limit had the largest multiplier and the jump stopped at 0.24 m.
  Sweep (``python -m latentoc sweep broad-jump``, warm-started): distance 0.27, 0.35, 0.38,
  0.41, 0.41, 0.43 m for tubes 0.005-0.16, 9-60 s per solve.  That is below the training
  jump's 0.73 m: phase 1's feasible point nearest the training fit jumps only 0.23-0.31 m.
  Adding 9 stance nodes in the last 30 ms before takeoff (``push_off_nodes``), where the 1 kHz
  check finds the needed centre of pressure 6-11 cm ahead of the toe, makes phase 1 fall into
  restoration (no feasible point in 1500 iterations), so it is off by default.  A uniformly
  denser stance grid (63 nodes, 5 ms) does not converge either (phase 1: 1500 iterations,
  violation 1e-3; 650 s), while its 1 kHz check is closer (centre of pressure -0.03 to -0.08 m,
  friction ratio 0.40).  The end point at tube 0.16 (32 stance nodes, ``solve --tube 0.16``):
  distance 0.42 m, time scale 0.965, 1 kHz check: flight residual 4e-14 body weights, friction
  ratio 0.56, centre of pressure 0.26 m outside the foot at 0.12 s where fz is 0.19 body
  weights, point-cone violation 0.13 body weights, torque-limit excess 6.6 N m, ZMP margin
  -0.05 m, COM margin +0.05 m.
* wrench samples between the nodes (``wrench_spacing``, :func:`wrench_rows`: the needed wrench
  in the cone of the loaded points, no force variables), tube 0.16, warm-started from the cold
  optimum (distance 0.346 m; its 1 kHz check: friction ratio 0.400, centre-of-pressure margin
  -0.062 m, ZMP margin -0.020 m, torque-limit excess 25 N m, point-cone violation 0.11 body
  weights): one sample per node interval (``0.005``): 1500 iterations without convergence
  (525 s, the node base rows left at 1e-3), distance 0.267 m, 1 kHz check -0.022 m, -0.009 m,
  9.9 N m, 0.08; three per interval (``0.0025``): the same stall (530 s), 0.245 m, -0.014 m,
  -0.005 m, 9.8 N m, 0.06.  The samples pull the 1 kHz numbers towards valid but the NLP does not
  converge, so they are off by default.  The cause is upstream of the transcription: along the
  training fit, the toe-pinned base (leg joints from the GP mean, whose noise variance is only
  6e-5: it interpolates the 120 Hz capture, jitter included) needs fz from -1.3 to 2.1 and fx
  from -2.6 to 3.7 body weights in the stance, and 0.22 (fz) and 0.55 (fx) body weights of it
  between 10 ms nodes; a noise floor (``beta3_max`` 1000) halves the between-node part
  (0.09, 0.25) but not the range.  Measured with ``multiplier_by_kind`` at tube 0.16: the tube
  does not bind (max sigma^2 0.069); without torque limits the same start reaches 0.60 m, with
  a looser contact schedule (flat foot 0.3 rad, ball 5 cm) 0.45 m.  With the noise floor in the
  NLP (``GPDMSettings(beta3_max=1000)``, cold two-phase solve, tube 0.16): phase 1 226 iterations
  (43 s, 0.29 m), phase 2 converges at 0.373 m (86 s in all), the tube now binds (max sigma^2
  0.1603), but the 1 kHz check is no better (centre of pressure -0.067 m, torque excess 33 N m),
  so the jump keeps the learned noise.
* the spline base (``base_model="spline"``, this version's default; 8 + 8 base control points, toe
  within 1 cm): along the training fit the needed wrench falls from the toe-pinned -1.3..2.1
  (fz) and -2.6..3.7 (fx) body weights to 0.59..1.05 and -0.35..0.81.  Cold two-phase solves
  (phase 1 423 iterations, 0.61 m; 2 shared cores, compiled rows): without wrench samples
  1.21 m at delta 0.005 and 1.24 m at 0.16 (111 iterations, 239 s), 1 kHz check at 0.16:
  friction ratio 0.48, centre-of-pressure margin -0.08 m, torque excess 26 N m; with samples
  every 5 ms in phase 2 (phase 1 without them: with them it did not converge in 1500 iterations,
  violation 0.01): 0.71 m at 0.005 and 0.85 m at 0.16 (324 iterations, 173 s), 1 kHz check at
  0.16: friction ratio 0.47 (at fz 0.2 body weights, 0.01 body weights over the cone), centre of
  pressure -0.012 m behind the loaded support (at heel-off), ZMP 0.0, COM 0.0, torque excess
  7.5 N m; samples every 2.5 ms (warm): 0.83 m and about the same check.  With 20 flight nodes
  the hip torque left its limit by 32 N m between them at 0.005; 40 nodes (10 ms): 1.9 N m.
  With a 5 mm foot tolerance (delta 0.16): 0.68 m, friction ratio 0.355, centre of pressure
  -0.3 mm, torque excess 4.6 N m, 672 iterations (335 s): the tolerance trades distance for
  validity.
* wrench samples also at every spline breakpoint of a contact phase, and 12 + 12 base control
  points (this version).  The accelerations of the cubic splines are piecewise linear with kinks
  at the breakpoints, so the needed wrench and the torques peak there: with 12 base control points
  and samples on the 5 ms grid only, the base fell freely for 3 ms at a knot between two samples
  (1 kHz normal force -21 N, centre of pressure undefined), at 1.21 m (delta 0.005); with samples
  at the knots the same solve keeps fz >= 5.6 N, friction ratio 0.42, centre of pressure -3.7 mm.
  With 8 base control points the feasible point nearest the training fit (phase 1) jumps 0.61 m
  and phase 2 0.71 m at delta 0.005; with 12, 0.74 m and 1.21 m.  The samples then also bound the
  torques of the joints no foot force enters (``torque_free``): the upper back's 6.1 N m excess at
  a base knot went, the largest 1 kHz excess in contact left is the knee's 4.1 N m at the same
  knot (the legs' torques depend on the split of the wrench between heel, ball and toe tip, which
  the samples do not have).  Sweep (warm-started, 2 shared cores, 40 flight nodes): 1.207 to
  1.236 m for delta 0.005-0.16.  Contact nodes at the knots instead (``knot_nodes``, with force
  variables): phase 1 0.76 m, but phase 2 took 1332 iterations (621 s) to end at 0.72 m, so it
  is off.  The largest
  1 kHz excess was then in the flight, between two 10 ms flight nodes: the hip's abduction torque
  rises by 130 N m within 25 ms and peaked 7.8 N m over its limit 5 ms from the nearest node
  (delta 0.16, cold); with 80 flight nodes (5 ms): 1.1 N m, 1.229 m instead of 1.236 m, 188 s
  instead of 146 s (phase 1 464 iterations instead of 384).  Sweep with 80 flight nodes: 1.202 to
  1.224 m for delta 0.005-0.16, 22-198 s per solve, 1 kHz torque excess 0.5-5.5 N m (in contact),
  friction ratio <= 0.448, centre of pressure and ZMP >= -3.8 mm.  The time scale sits at its
  bound 1.15 at every delta; with the durations fixed (``time_scale=False``, cold): 0.786 m at
  delta 0.005 (phase 1 0.415 m) and 1.030 m at 0.16 (tube not binding, max sigma^2 0.074),
  1 kHz torque excess 2.4 and 0.2 N m, centre of pressure -8.6 and -2.5 mm.
* the exact Hessian (``hessian="exact"``, this version; compiled node Hessians on 2 threads).
  Delta 0.16, free time scale, cold: phase 1 39 iterations (22 s) against 433 (248 s) with L-BFGS,
  phase 2 177 iterations (179 s) against 188, 1.230 m.  With the training durations
  (``time_scale=False``, the packaged problem now): sweep 1.006, 1.020, 1.030, 1.032, 1.034,
  1.034 m for delta 0.005-0.16 (the L-BFGS solve had stopped at 0.786 m at 0.005), 46-120 s per
  solve (70-140 iterations), the tube binding at every delta, 1 kHz torque excess 0.07-2.0 N m,
  friction ratio <= 0.475, centre of pressure and ZMP >= -3.9 mm.  Per iteration the Hessian
  takes 0.32 s and the constraint Jacobian 0.15 s.
* Ipopt's OpenBLAS on one thread (its spinning workers had competed with the threaded node
  evaluations, :func:`latentoc.solver.load_ipopt`) and the compiled blocks found on disk from their
  rows (build 94 s -> 8.7 s, :func:`.lifted.compile_node_rows`), this version: sweep 88, 52, 53,
  36, 46, 53 s per solve (63-128 iterations), the same distances (1.006-1.035 m); per iteration
  the Hessian 0.26 s, the Jacobian 0.10 s, the rest of Ipopt 0.19 s.
* the sweep's warm starts with the previous optimum's multipliers (:data:`WARM_START_OPTIONS`),
  this version: 80, 32, 75, 28, 30, 13 s per solve (128, 62, 150, 57, 66, 38 iterations), the
  same distances to 1 mm, 5 min 15 s for the sweep.  Ipopt's timing statistics (phase 2 at
  delta 0.005, 30 iterations, 0.47 s each): Lagrangian Hessian 0.21 s, constraint Jacobian
  0.08 s, the linear solves (MUMPS, KKT of 785 variables and 13706 rows, 296k Jacobian
  nonzeros) 0.15 s.  Per evaluation of the node Hessians (2 threads): flight nodes 81 ms (80
  nodes), wrench samples 64 ms (124), contact nodes 43 ms (94), tube 35 ms (259), pitch rate
  35 ms (159).  Tried and not kept: ``mu_oracle probing`` (no convergence in 10 min),
  ``-march=native`` (12 % on the tube Hessian, a recompile of every block), MUMPS orderings
  (phase 2 at 0.005, default 140 iterations in 78 s: METIS 140 in 73 s, AMD 122 in 69 s, QAMD
  138 in 75 s, the same distance; 0.49-0.56 s per iteration).  Ipopt's log of that solve: the
  Hessian is regularised (wrong inertia) in most iterations, by up to 1e4 early on and 0.1-1
  later, with primal steps of 0.01-0.3 in the middle third; the inertia-free curvature test
  (``neg_curv_test_tol`` 1e-12 or 1e-11) instead took 445 iterations (253 s) to another local
  optimum, 0.786 m.  Phase 2 straight from the training start, with no phase 1: 151 iterations
  to 1.0066 m, no saving over phase 1's 38 cheaper ones plus 128.
* the right joints' torque rows left out (:attr:`RowModel.unmirrored`; they repeated the left's
  exactly) and the node rows computed about the base's position and velocity
  (:func:`_galilean`), this version: 8912 rows instead of 13706, 181k inequality-Jacobian
  nonzeros instead of 284k; phase 2 at delta 0.005 from the same phase-1 point 122 iterations in
  57 s (140 in 78 s before), the linear solves 0.12 s per iteration (0.15).  The node Hessians
  lost 10-16 % of their instructions, but their evaluation times hardly moved (contact 38 ms,
  wrench samples 64 ms, flight 80 ms, tube 38 ms, pitch rate 37 ms): per iteration the
  Hessian still takes 0.25 s, the Jacobian 0.10 s.  Cold solves (phase 1 + phase 2) at delta
  0.005, 0.02, 0.08: 104, 80, 85 s (37-38 + 186, 141, 156 iterations).  Tried there and not
  kept, as no setting won at every delta: ``adaptive_mu_globalization kkt-error`` 53, 77, 81 s;
  ``bound_mult_init_method mu-based`` 55, 92 s; phase 2 alone from the old phase-1 point:
  ``obj_scaling_factor`` 10 / 0.1 110 / 140 iterations, ``nlp_scaling_max_gradient`` 10 133,
  ``alpha_for_y min-dual-infeas`` 182, ``recalc_y`` 122, ``mu_strategy monotone`` (mu_init 0.01)
  123; the Lagrangian Hessian without the flight nodes' curvature (82 ms less per iteration,
  an inexact Hessian): 84 and 65 s at 0.005 and 0.02.  The split of the node Hessians at the
  GP mean (J_z^T H_R J_z plus the kernels' curvature, instead of CasADi's forward-over-reverse
  through the whole node) agreed to 1e-12 but had more instructions for the flight node
  (1.74M against 1.04M) and the contact node, fewer only for the wrench samples.  The warm sweep
  of this version stayed in a worse local optimum (1.013 m at delta 0.02 against 1.031 m cold,
  1.014 m at 0.16 after 1.015 m at 0.08), so the sweep now solves each tube warm and cold and
  keeps the better (:mod:`.problem`, ``sweep_starts``): 1.008, 1.011, 1.031, 1.032, 1.034,
  1.035 m, 10 min 17 s.  Also tried and not kept: a feasibility solve with the wrench samples
  between phase 1 and phase 2 (72 and 86 iterations; 101 s and 109 s in all at delta 0.005 and
  0.02, against 104 s and 80 s); the tube Hessian in closed form (K^-1 products, 232k
  instructions against CasADi's 220k, the same 37-44 ms for the 259 points).
* phase 2 from the same phase-1 point (another 2-core machine, 0.2-0.3 s per iteration), delta
  0.005, 0.02, 0.08, default settings 186, 141, 156 iterations (1.0082, 1.0309, 1.0317 m):
  ``adaptive_mu_globalization kkt-error`` 98, 172, 117 (1.0081, 1.0309, 1.0302 m); bound and slack
  pushes of 1e-6 (the point is feasible but for the wrench samples, whose rows start 0.13
  violated) 129 and 164 at 0.005 and 0.02; phase 1's multipliers as Ipopt's warm start (the
  wrench samples' at 0, :data:`WARM_START_OPTIONS`) 165 and 185, 1.0061 m at 0.005.  Each
  setting moves the count by up to 40 % either way from tube to tube; none is kept.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

import casadi as ca
import numpy as np
import pinocchio as pin

from ..dynamics import SymbolicModel
from ..gpdm import GPDM
from ..solver import ipopt_solver, jit_enabled
from ..spline import BSpline
from .base import base_function
from .contact import MU, TOE_PAD, FootGeometry, anchor_function, joint_embedding, point_generalized_force, point_forces, \
    points_function, toe_wrench
from .flight import GRAVITY, ballistic_base, cumulative_trapezoid_matrix, flight_functions
from .lifted import NodeRows, compile_node_rows, lifted_hessian, lifted_rows, select_rows
from .phases import Phases
from .support_polygon import symbolic_rows
from .torque_limits import TrainingDynamics
from .training import RIGHT_TOE, TOE
from .zmp import G

SAGITTAL_ROWS = [0, 2, 4]
JUMP_HESSIANS = ("limited-memory", "exact")
# Ipopt's warm start from a neighbouring solve's primal and dual point (the sweep's continuation
# in delta): the start and its multipliers pushed only 1e-5 off their bounds, the barrier started
# small.  Delta 0.005 -> 0.01 from the 0.005 optimum: 66 iterations (37 s) against 103 (54 s) from
# the primal point alone, same distance 1.0204 m; pushes of 1e-6 with mu 1e-5: 98 iterations;
# mu_init 1e-3: 66; with mu_strategy monotone: 78 (measured, issue 6)
WARM_START_OPTIONS = {"ipopt.warm_start_init_point": "yes", "ipopt.mu_init": 1e-4,
                      "ipopt.warm_start_bound_push": 1e-5, "ipopt.warm_start_mult_bound_push": 1e-5,
                      "ipopt.warm_start_slack_bound_push": 1e-5}


@dataclass
class JumpSettings:
    """Table 5 parameters and discretisation."""

    tube: float = 0.0005
    mu: float = MU
    n_control: int = 21  # paper 11; 11 cannot follow the push-off (see the module doc)
    n_stance: int = 32  # contact nodes every 10 ms: sparser grids let the motion wobble between nodes
    push_off_nodes: tuple[float, int] = (0.0, 0)  # (span s, n): n more stance nodes just before takeoff
    n_flight: int = 80  # every 5 ms; the hip torque left its limit between flight nodes by 32 N m with 20, 7.8 with 40
    n_land: int = 62
    n_phi_stance: int = 8  # 5 cannot follow the captured stance base (measured, issue 6)
    n_phi_land: int = 6
    base_model: str = "spline"  # "spline": the base's own splines; "pinned": toe-pinned (foot pitch splines)
    # control points of the (x, z, pitch) base spline in stance and in the landing ("spline"); with
    # 8 each the feasible point nearest the training fit jumped 0.61 m (12: 0.74 m)
    n_base_stance: int = 12
    n_base_land: int = 12
    foot_tolerance: float = 0.01  # m the toe tip may move from its ground point in contact ("spline")
    flight_substeps: int = 2  # trapezoid steps of the pitch rate per flight node interval
    contact_model: str = "schedule"  # "schedule" (training contact times), "complementarity" or "free"
    complementarity_eps: float = 1e-4  # body weights x metres ("complementarity" only)
    ball_tolerance: float = 0.02  # m the ball may sink below the ground (the toe joint's capture noise)
    contact_tolerance: float = 0.01  # m: a loaded ball stays within this of the ground ("schedule")
    flat_foot_pitch: float = 0.05  # rad: a loaded heel keeps the foot this flat ("schedule", ~1 cm at the heel)
    tube_spacing: float = 0.005  # s; the tube (cheap: GP variance only) on this grid, not only at nodes
    wrench_spacing: float = 0.0  # s; > 0: the needed wrench in its cone on this grid between contact nodes
    # contact nodes also at the latent and base splines' breakpoints (their accelerations kink
    # there).  Off by default: at delta 0.005 phase 2 took 1332 iterations (621 s) and ended at
    # 0.72 m, below its own phase 1 (0.76 m); with wrench samples there instead: 1.21 m, 169 it
    knot_nodes: bool = False
    max_iter: int = 400
    tol: float = 1e-5
    hessian: str = "limited-memory"  # or "exact": compiled Hessians of the row blocks (:func:`.lifted.lifted_hessian`)
    print_level: int = 0
    torque_limits: bool = True
    polygon: bool = True
    # one free factor k on the durations of all phases (t = k s, module doc); the packaged problem
    # (problems/broad-jump.toml) keeps the training durations: free, k sits at its upper bound
    time_scale: bool = True
    time_scale_bounds: tuple[float, float] = (0.85, 1.15)
    two_phase: bool = True  # phase 1 feasibility near the training fit, then phase 2 max distance
    jit: bool = True  # node rows and Jacobians compiled to C (:mod:`.lifted`)


@dataclass
class JumpNLP:
    """Built NLP and the pieces needed to read a solution."""

    solver: ca.Function
    x0: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    lbg: np.ndarray
    ubg: np.ndarray
    unpack: ca.Function
    names: list[str]
    build_time: float
    meta: dict = field(default_factory=dict)


def anchored_function(sym: SymbolicModel, smap, gpdm: GPDM, geom: FootGeometry) -> ca.Function:
    """(x, xd, xdd, phi, phid, phidd, x_pin) -> b, bd, bdd of the toe-pinned base."""
    d = gpdm.latent_dim
    x, xd, xdd = (ca.SX.sym(n, d) for n in ("x", "xd", "xdd"))
    phi, phid, phidd, xpin = (ca.SX.sym(n) for n in ("phi", "phid", "phidd", "x_pin"))
    y = gpdm.mean_function()(x)
    b = anchor_function(sym, smap, geom)(y, phi, xpin)
    z, zd, zdd = ca.vertcat(x, phi), ca.vertcat(xd, phid), ca.vertcat(xdd, phidd)
    bd = ca.jtimes(b, z, zd)
    bdd = ca.jtimes(b, z, zdd) + ca.jtimes(bd, z, zd)
    return ca.Function("anchored_base", [x, xd, xdd, phi, phid, phidd, xpin], [b, bd, bdd],
                       ["x", "xd", "xdd", "phi", "phid", "phidd", "x_pin"], ["b", "bd", "bdd"])


def _joint_motion(gpdm: GPDM, smap, x, xd, xdd):
    """Learned-coordinate (y, yd, ydd) through the GP mean (Eq. 18, 26-28) and the embedding E."""
    y = gpdm.mean_function()(x)
    yd = ca.jtimes(y, x, xd)
    ydd = ca.jtimes(y, x, xdd) + ca.jtimes(yd, x, xd)
    E = ca.DM(joint_embedding(smap))
    return y, E @ y, E @ yd, E @ ydd


def _configuration(b, bd, bdd, qj, vj, aj):
    q7, v6, a6 = base_function()(b, bd, bdd)
    return ca.vertcat(q7, qj), ca.vertcat(v6, vj), ca.vertcat(a6, aj)


@dataclass
class RowModel:
    """What the node rows need: models, geometry, limits, scales."""

    sym: SymbolicModel
    smap: object
    gpdm: GPDM
    geom: FootGeometry
    limits: TrainingDynamics
    mu: float
    mass: float
    base_model: str = "spline"  # "spline" (own base inputs) or "pinned" (toe-pinned, foot pitch inputs)

    @property
    def weight(self) -> float:
        return self.mass * G

    @property
    def active(self) -> np.ndarray:
        """Joints with a torque range (the others vanish by symmetry; checked in verify)."""
        return np.where(self.limits.tau_max - self.limits.tau_min > 1e-6)[0]

    @property
    def torque_scale(self) -> np.ndarray:
        a = self.active
        return np.maximum(self.limits.tau_max[a] - self.limits.tau_min[a], 1.0)

    @property
    def force_free(self) -> np.ndarray:
        """Positions in :attr:`active` of the joints that no foot force enters (the trunk, neck,
        head and arms: not on the path from the base to a toe tip), so their torque is the
        motion's alone, known without the force split.  For the legs the split matters: realised
        at the heel or at the ball (with the toe tip), the same sagittal wrench gave torques 5 N m
        apart at the knee and 20 N m at the hip's abduction (the points' lateral offsets)."""
        m = self.sym.model
        legs = {j for f in (TOE, RIGHT_TOE) for j in m.supports[m.frames[m.getFrameId(f)].parentJoint]}
        joint_of_v = np.concatenate([[j] * m.joints[j].nv for j in range(1, m.njoints)])
        return np.array([i for i, a in enumerate(self.active) if joint_of_v[6 + a] not in legs], int)

    @property
    def unmirrored(self) -> np.ndarray:
        """Positions in :attr:`active` whose torque rows the NLP keeps: all but the right side's
        copies.  The model and the motion are mirror images, so a right joint's torque is its left
        partner's times the mirror factor (to rounding), and when its limits are the mirrored ones
        too its rows repeat the left's (13706 -> 8912 rows; duplicated active rows also make the
        constraint Jacobian rank-deficient).  Limits that are not mirror images keep every row."""
        a = self.active
        pos = {int(j): k for k, j in enumerate(a)}
        lo, hi = self.limits.tau_min, self.limits.tau_max
        right = []
        for r_q, y_idx, f in self.smap.copied:
            r, left = r_q - 7, int(self.smap.learned_q[y_idx]) - 7
            mlo, mhi = (lo[left], hi[left]) if f > 0 else (-hi[left], -lo[left])
            tol = 1e-9 * max(1.0, abs(hi[left]), abs(lo[left]))
            if abs(lo[r] - mlo) > tol or abs(hi[r] - mhi) > tol:
                return np.arange(len(a))
            if r in pos:
                right.append(pos[r])
        return np.setdiff1d(np.arange(len(a)), right)

    def torque_rows(self, tau_joint):
        """Joint torques of the active joints in N m; build_nlp scales them by the limit range
        outside the compiled rows, so that new limits (margins) need no new C code."""
        return tau_joint[self.active.tolist()]


BASE_INPUTS = {"pinned": 4, "spline": 10}  # contact-phase base inputs after (x, xd, xdd), x_pin last


def _contact_base(rm: RowModel, u: ca.SX):
    """(b, bd, bdd, x_pin) of a contact-phase input u = (x, xd, xdd, base inputs, ...): for
    ``"pinned"`` the toe-pinned base of (phi, phid, phidd, x_pin); for ``"spline"`` the inputs
    (b, bd, bdd, x_pin) themselves."""
    d = rm.gpdm.latent_dim
    x, xd, xdd = u[:d], u[d:2 * d], u[2 * d:3 * d]
    if rm.base_model == "pinned":
        phi, phid, phidd, xpin = (u[3 * d + k] for k in range(4))
        b, bd, bdd = anchored_function(rm.sym, rm.smap, rm.gpdm, rm.geom)(x, xd, xdd, phi, phid, phidd, xpin)
        return b, bd, bdd, xpin
    r = u[3 * d:3 * d + 10]
    return r[0:3], r[3:6], r[6:9], r[9]


def _galilean(b, bd):
    """The base pose and velocity without their translation: (0, 0, pitch), (0, 0, pitch rate).

    A uniform translation and a uniform velocity of the whole body change neither the joint
    torques nor the base rows of RNEA (the base wrench in the base frame), nor the Jacobians of
    the contact points: the gravity field is uniform and Newton's laws hold in every inertial
    frame (numeric RNEA: equal to 7e-15 of 393 N m).  Node rows computed this way do not depend
    on the base's position and linear velocity, so their compiled Hessians skip that (numerically
    zero) curvature; point positions add the translation back (:func:`_world_points`)."""
    return ca.vertcat(0, 0, b[2]), ca.vertcat(0, 0, bd[2])


def _world_points(rm: RowModel, q, shift):
    """Heel, ball and toe points (3 x 3) of the relative pose q (:func:`_galilean`), moved by
    the base translation ``shift`` (x, z)."""
    return points_function(rm.sym, rm.geom)(q) + ca.repmat(ca.vertcat(shift[0], 0, shift[1]), 1, 3)


def _anchored_dynamics(rm: RowModel, u: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX]:
    """The relative q (:func:`_galilean`), rnea(q, v, a) and the base translation (x, z) of the
    contact-phase motion whose inputs start with u = (x, xd, xdd, base inputs, ...)
    (:func:`_contact_base`)."""
    d = rm.gpdm.latent_dim
    b, bd, bdd, _ = _contact_base(rm, u)
    _, qj, vj, aj = _joint_motion(rm.gpdm, rm.smap, u[:d], u[d:2 * d], u[2 * d:3 * d])
    q, v, a = _configuration(*_galilean(b, bd), bdd, qj, vj, aj)
    return q, rm.sym.rnea(q, v, a), b[:2]


def contact_rows(rm: RowModel) -> tuple[NodeRows, dict[str, slice]]:
    """Rows of one contact node, u = (x, xd, xdd, base inputs, lam[6]) (:func:`_contact_base`).

    The point forces of the heel, ball and toe (``lam`` in body weights on the friction-pyramid
    edges, :mod:`.contact`) act on their own bodies.  Rows: sagittal base rows of RNEA minus
    sum J^T f (body weights); joint torques (scaled to the limit range); heel and ball
    complementarity and ball height; the ZMP (centre of pressure of both feet) in the support
    polygon, multiplied by the normal force so that it stays smooth as fz -> 0; the projected
    COM in it.  Toe-pinned base: the foot pitch phi >= 0 (``heel_up``).  Spline base: the toe
    tip's offset from its ground point (x_pin, 0) (``toe_position``) and the heel height.
    """
    d, W = rm.gpdm.latent_dim, rm.weight
    nb = BASE_INPUTS[rm.base_model]
    u = ca.SX.sym("u", 3 * d + nb + 6)
    lam = u[3 * d + nb:]
    q, tau, shift = _anchored_dynamics(rm, u)
    gen = point_generalized_force(rm.sym, rm.geom, q, point_forces(lam * W, rm.mu))
    P = _world_points(rm, q, shift)
    w = toe_wrench(lam, P, rm.mu)  # body weights, moment about the toe tip
    fz, my = w[2], w[4]
    heel, toe = P[:2, 0], P[:2, 2]
    rows = symbolic_rows(heel, toe)
    # ZMP x = toe_x - my / fz, y = 0; rows(p) are affine in p: fz rows(p) = rows_h(fz p, fz)
    parts = {
        "dynamics": (tau - gen)[SAGITTAL_ROWS] / W,
        "torque": rm.torque_rows((tau - gen)[6:]),
        "heel_complementarity": P[2, 0] * (lam[0] + lam[1]),
        "ball_complementarity": P[2, 1] * (lam[2] + lam[3]),
        "ball_height": P[2, 1],
    }
    if rm.base_model == "pinned":
        parts["heel_up"] = u[3 * d]
    else:
        parts["toe_position"] = ca.vertcat(P[0, 2] - _contact_base(rm, u)[3], P[2, 2])
        parts["heel_height"] = P[2, 0]
    parts["zmp_polygon"] = _homogeneous_rows(heel, toe, ca.vertcat(toe[0] * fz - my, 0), fz)
    parts["com_polygon"] = rows(rm.sym.com(q)[:2] + ca.vertcat(shift[0], 0))
    return _node_rows("jump_contact_node" if rm.base_model == "pinned" else "jump_contact_node_spline_base",
                      u, parts)


def wrench_rows(rm: RowModel) -> tuple[NodeRows, dict[str, slice]]:
    """Rows of the contact wrench the motion needs at a sample between contact nodes,
    u = (x, xd, xdd, base inputs) (:func:`_contact_base`).

    No force variables: the three sagittal base rows of RNEA, solved for the (fx, fz, my) of
    each (symmetric) foot at its toe tip (as :func:`.verify.sagittal_contact_wrench`), must lie
    in the wrench cone of the foot's loaded points.  In the sagittal plane a wrench is made of
    point forces in their friction cones exactly when fz >= 0, |fx| <= mu fz and the centre of
    pressure ``toe_x - my / fz`` lies between the rearmost loaded point and the toe tip, so the
    rows are (body weights, all >= 0, homogeneous in fz so that they stay smooth as fz -> 0):
    ``wrench_normal`` fz; ``wrench_friction`` mu fz -+ fx; ``cop_front`` my (not ahead of the
    toe tip); ``cop_heel``, ``cop_ball``, ``cop_pad``: (toe_x - back_x) fz - my with the heel,
    the ball or a :data:`TOE_PAD` patch as the rearmost loaded point (chosen per sample by the
    contact schedule in :func:`build_nlp`); ``torque_free``: the torques of the joints no foot
    force enters (:attr:`RowModel.force_free`), for their limits.  The nodes alone left the needed
    wrench free to leave the cone and the foot between them (measured, issue 6).
    """
    W = rm.weight
    u = ca.SX.sym("u", 3 * rm.gpdm.latent_dim + BASE_INPUTS[rm.base_model])
    q, tau, shift = _anchored_dynamics(rm, u)
    J = rm.sym.frame_jacobian(TOE)(q) + rm.sym.frame_jacobian(RIGHT_TOE)(q)
    fx, fz, my = ca.vertsplit(ca.solve(J.T[SAGITTAL_ROWS, SAGITTAL_ROWS], tau[SAGITTAL_ROWS]) / W)
    P = _world_points(rm, q, shift)
    toe_x = P[0, 2]
    parts = {
        "wrench_normal": fz,
        "wrench_friction": ca.vertcat(rm.mu * fz - fx, rm.mu * fz + fx),
        "cop_front": my,
        "cop_heel": (toe_x - P[0, 0]) * fz - my,
        "cop_ball": (toe_x - P[0, 1]) * fz - my,
        "cop_pad": TOE_PAD * fz - my,
        "torque_free": rm.torque_rows(tau[6:])[rm.force_free.tolist()],
    }
    return _node_rows("jump_wrench_sample" if rm.base_model == "pinned" else "jump_wrench_sample_spline_base",
                      u, parts)


def _homogeneous_rows(heel, toe, p_scaled, s):
    """s * rows(p_scaled / s) of the support polygon (:func:`symbolic_rows`), without the division."""
    V = [(heel[0], -heel[1]), (toe[0], -toe[1]), (toe[0], toe[1]), (heel[0], heel[1])]
    out = []
    for i in range(4):
        (x0, y0), (x1, y1) = V[i], V[(i + 1) % 4]
        ex, ey = x1 - x0, y1 - y0
        out.append(-(ex * (p_scaled[1] - y0 * s) - ey * (p_scaled[0] - x0 * s)) / ca.sqrt(ex * ex + ey * ey))
    return ca.vertcat(*out)


def _node_rows(name: str, u: ca.SX, parts: dict) -> tuple[NodeRows, dict[str, slice]]:
    layout, off = {}, 0
    for k, e in parts.items():
        layout[k] = slice(off, off + e.numel())
        off += e.numel()
    return NodeRows.from_expression(name, u, ca.vertcat(*[ca.vec(e) for e in parts.values()]), lazy=True), layout


def _ballistic_com(c_to, cd_to, tt):
    """COM position and velocity (x, z) at flight time tt from the takeoff state."""
    g = ca.DM(GRAVITY)
    return c_to + cd_to * tt + 0.5 * g * tt ** 2, cd_to + g * tt


def _flight_base(rm: RowModel, x, xd, xdd, p, L, c, cd):
    """Base (b, bd, bdd) of the flight (:mod:`.flight`) for pitch p, momentum L and the COM at
    c with velocity cd, accelerating at g."""
    fns = flight_functions(rm.sym, rm.smap, rm.gpdm)
    pd, pdd = fns["pitch_rate"](x, xd, xdd, L)
    return fns["base"](x, xd, xdd, p, pd, pdd, c, cd, ca.DM(GRAVITY))


def flight_rows(rm: RowModel) -> tuple[NodeRows, dict[str, slice]]:
    """Rows of one flight node, u = (x, xd, xdd, pitch, L, c_to[2], cd_to[2], t - takeoff):
    joint torques of the ballistic motion and the heel, ball and toe heights."""
    d = rm.gpdm.latent_dim
    u = ca.SX.sym("u", 3 * d + 7)
    x, xd, xdd = u[:d], u[d:2 * d], u[2 * d:3 * d]
    p, L, c_to, cd_to, tt = u[3 * d], u[3 * d + 1], u[3 * d + 2:3 * d + 4], u[3 * d + 4:3 * d + 6], u[3 * d + 6]
    # the motion about the COM (:func:`_galilean`): COM at the origin at rest, accelerating at g;
    # the COM's ballistic position c(t) moves the points
    b, bd, bdd = _flight_base(rm, x, xd, xdd, p, L, ca.DM.zeros(2), ca.DM.zeros(2))
    _, qj, vj, aj = _joint_motion(rm.gpdm, rm.smap, x, xd, xdd)
    q, v, a = _configuration(b, bd, bdd, qj, vj, aj)
    tau = rm.sym.rnea(q, v, a)
    P = _world_points(rm, q, _ballistic_com(c_to, cd_to, tt)[0])
    return _node_rows("jump_flight_node", u, {"torque": rm.torque_rows(tau[6:]), "flight_clearance": P[2, :].T})


def takeoff_rows(rm: RowModel) -> tuple[NodeRows, dict[str, slice]]:
    """Takeoff state rows, u = (x, xd, xdd, base inputs, c_to[2], cd_to[2], L, pitch): the flight
    variables equal the stance's COM, COM velocity, angular momentum and pitch at takeoff.
    Base inputs (:func:`_contact_base`, without x_pin): toe-pinned (phi, phid, phidd) with the
    toe at x = 0, or the spline base's (b, bd, bdd)."""
    d = rm.gpdm.latent_dim
    nb = BASE_INPUTS[rm.base_model] - 1
    u = ca.SX.sym("u", 3 * d + nb + 6)
    x, xd = u[:d], u[d:2 * d]
    c_to, cd_to, L, p = u[3 * d + nb:3 * d + nb + 2], u[3 * d + nb + 2:3 * d + nb + 4], u[3 * d + nb + 4], u[-1]
    b, bd, _, _ = _contact_base(rm, ca.vertcat(u[:3 * d + nb], 0.0))
    c, cd, Lm = flight_functions(rm.sym, rm.smap, rm.gpdm)["momentum"](x, xd, b, bd)
    name = "jump_takeoff" if rm.base_model == "pinned" else "jump_takeoff_spline_base"
    return _node_rows(name, u, {"takeoff": ca.vertcat(c - c_to, cd - cd_to, Lm - L, b[2] - p)})


def touchdown_rows(rm: RowModel) -> tuple[NodeRows, dict[str, slice]]:
    """Touchdown rows, u = (x, xd, xdd, base inputs, pitch, L, c_to[2], cd_to[2], t_td - takeoff,
    impulse[6]) with the landing's base inputs (:func:`_contact_base`; toe-pinned: (phi, phid,
    phidd, x_L), spline: (b, bd, bdd, x_L)): the flight's base pose meets the landing's pose, and
    the inelastic impact ``M_bb (v+ - v-) = (sum J^T Pi)_base`` (module doc; impulse in units
    of 0.1 s of body weight, on the friction-pyramid edges like the forces)."""
    d, W = rm.gpdm.latent_dim, rm.weight
    nb = BASE_INPUTS[rm.base_model]
    u = ca.SX.sym("u", 3 * d + nb + 13)
    x, xd, xdd = u[:d], u[d:2 * d], u[2 * d:3 * d]
    o = 3 * d + nb
    p, L, c_to, cd_to, tt = u[o], u[o + 1], u[o + 2:o + 4], u[o + 4:o + 6], u[o + 6]
    imp = u[o + 7:]
    bm, bdm, _ = _flight_base(rm, x, xd, xdd, p, L, *_ballistic_com(c_to, cd_to, tt))
    bp, bdp, _, _ = _contact_base(rm, u)
    _, qj, _, _ = _joint_motion(rm.gpdm, rm.smap, x, xd, xdd)
    z3 = ca.DM.zeros(3)
    q = _configuration(bp, z3, z3, qj, 0 * qj, 0 * qj)[0]
    v_minus = base_function()(bp, bdm, z3)[1]
    v_plus = base_function()(bp, bdp, z3)[1]
    Mbb = rm.sym.mass_matrix(q)[:6, :6]
    gen = point_generalized_force(rm.sym, rm.geom, q, point_forces(imp * W * 0.1, rm.mu))
    impact = Mbb @ (v_plus - v_minus) - gen[:6]
    name = "jump_touchdown" if rm.base_model == "pinned" else "jump_touchdown_spline_base"
    return _node_rows(name, u, {"touchdown_position": bm - bp, "impact": impact[SAGITTAL_ROWS] / W})


def pitch_rate_rows(rm: RowModel) -> tuple[NodeRows, dict[str, slice]]:
    """Pitch rate of the flight, u = (x, xd, xdd, L): pd = (L - h) / I (:mod:`.flight`)."""
    d = rm.gpdm.latent_dim
    u = ca.SX.sym("u", 3 * d + 1)
    pd, _ = flight_functions(rm.sym, rm.smap, rm.gpdm)["pitch_rate"](u[:d], u[d:2 * d], u[2 * d:3 * d], u[3 * d])
    return _node_rows("jump_pitch_rate", u, {"pitch_rate": pd})


def tube_rows(rm: RowModel) -> tuple[NodeRows, dict[str, slice]]:
    """GP variance sigma^2(x) (Eq. 19, 29), u = x."""
    u = ca.SX.sym("u", rm.gpdm.latent_dim)
    return _node_rows("jump_tube", u, {"tube": rm.gpdm.variance_function()(u)})


_ROW_CACHE: dict = {}
ROW_BLOCKS = (contact_rows, flight_rows, takeoff_rows, touchdown_rows, pitch_rate_rows, tube_rows)
OPTIONAL_BLOCKS = (wrench_rows,)  # built (and compiled) only when asked for


def node_rows(rm: RowModel, jit: bool = True, optional: tuple[str, ...] = (), hessian: bool = False
              ) -> dict[str, tuple[NodeRows, dict[str, slice]]]:
    """The row blocks of the jump and the ``optional`` ones named (e.g. ``"wrench_rows"``),
    compiled, with their Hessians if ``hessian``; each block cached per model, GPDM, geometry,
    limits, mu and whether it has its Hessian."""
    jit = jit and jit_enabled()  # with LATENTOC_JIT=0 the jit and plain blocks are the same
    key = (id(rm.sym), id(rm.gpdm), id(rm.geom), id(rm.limits), rm.mu, rm.base_model, jit, hessian)
    known = {f.__name__: f for f in OPTIONAL_BLOCKS}
    unknown = [n for n in optional if n not in known]
    if unknown:
        raise ValueError(f"unknown optional row blocks {unknown}; known: {sorted(known)}")
    wanted = list(ROW_BLOCKS) + [known[n] for n in optional]
    cached = _ROW_CACHE.setdefault(key, (rm, {}))[1]  # keep rm alive for the ids
    missing = [f for f in wanted if f.__name__ not in cached]
    if missing:
        raw = {f.__name__: f(rm) for f in missing}
        compiled = compile_node_rows({k: v[0] for k, v in raw.items()}, jit=jit, hessian=hessian)
        cached.update({k: (compiled[k], raw[k][1]) for k in raw})
    return {f.__name__: cached[f.__name__] for f in wanted}


def _basis(sp: BSpline, t: np.ndarray, offset: float = 0.0) -> list[np.ndarray]:
    return [sp.basis(np.clip(t - offset, 0, sp.duration), k) for k in range(3)]


def _spline_rows(sp: BSpline, C: ca.MX, t: np.ndarray, offset: float = 0.0) -> ca.MX:
    """Value, first and second time derivative of the spline with coefficients C (m x n) at
    times t, stacked: (3 n) x K, affine in C."""
    return ca.vertcat(*[(ca.sparsify(ca.DM(B)) @ C).T for B in _basis(sp, t, offset)])


def _time_scaled(R: ca.MX, n: int, ik) -> ca.MX:
    """Rows (value, d/ds, d2/ds2; n each) of a spline in nominal time s as real-time ones,
    t = k s: the derivatives times 1/k and 1/k^2 (``ik`` = 1/k, None for k = 1)."""
    if ik is None:
        return R
    return ca.vertcat(R[:n, :], ik * R[n:2 * n, :], ik ** 2 * R[2 * n:, :])


def _between(nodes: np.ndarray, spacing: float) -> np.ndarray:
    """Sample times about ``spacing`` apart strictly between consecutive node times."""
    out = [np.linspace(a, b, max(1, int(np.ceil((b - a) / spacing - 1e-9))) + 1)[1:-1]
           for a, b in zip(nodes[:-1], nodes[1:])]
    return np.concatenate(out) if out else np.zeros(0)


def _merge_samples(samples: np.ndarray, extra: np.ndarray, nodes: np.ndarray, gap: float = 1e-4) -> np.ndarray:
    """``samples`` and ``extra`` sorted, without the extra times within ``gap`` of a node, a
    sample or an earlier extra time."""
    taken = list(np.concatenate([nodes, samples]))
    keep = []
    for t in np.sort(extra):
        if not taken or np.min(np.abs(np.asarray(taken) - t)) > gap:
            keep.append(t)
            taken.append(t)
    return np.sort(np.concatenate([samples, np.asarray(keep, float)]))


def _layout_indices(layout: dict[str, slice], n_out: int, K: int, per_node: list[list[str]],
                    subsets: dict[str, np.ndarray] | None = None) -> tuple[list[int], list[str]]:
    """Row indices (node-major) and names of the chosen parts of each node; ``subsets`` keeps
    only the given positions of a part."""
    idx, names = [], []
    subsets = subsets or {}
    for k in range(K):
        for part in per_node[k]:
            s = layout[part]
            rows = s.start + np.asarray(subsets[part]) if part in subsets else np.arange(s.start, s.stop)
            idx.extend((k * n_out + rows).tolist())
            names.extend([part] * len(rows))
    return idx, names


def build_nlp(model: pin.Model, smap, gpdm: GPDM, geom: FootGeometry, phases: Phases,
              limits: TrainingDynamics, settings: JumpSettings, init: dict,
              sym: SymbolicModel | None = None, warm_start: bool = False) -> JumpNLP:
    """Assemble the NLP; ``init`` holds initial guesses (P, phi_s, phi_l, x_L, lam).

    ``warm_start``: Ipopt starts from given multipliers too (``lam_g0``, ``lam_x0`` of a
    neighbouring solve, :data:`WARM_START_OPTIONS`) instead of pushing the start into the
    interior with fresh ones."""
    t0 = time.perf_counter()
    s = settings
    if s.hessian not in JUMP_HESSIANS:
        raise ValueError(f"hessian must be one of {JUMP_HESSIANS}, got {s.hessian!r}")
    exact = s.hessian == "exact"
    sym = sym or SymbolicModel(model)
    mass = float(sum(i.mass for i in model.inertias))
    rm = RowModel(sym, smap, gpdm, geom, limits, s.mu, mass, s.base_model)
    blocks = node_rows(rm, jit=s.jit, optional=("wrench_rows",) if s.wrench_spacing > 0 else (), hessian=exact)
    dlat = gpdm.latent_dim
    grid = phases.grid(s.n_stance, s.n_flight, s.n_land, s.push_off_nodes)
    T = phases.duration
    sp = BSpline(s.n_control, T)
    if s.base_model not in BASE_INPUTS:
        raise ValueError(f"base_model must be one of {sorted(BASE_INPUTS)}, got {s.base_model!r}")
    spline_base = s.base_model == "spline"
    if spline_base and s.contact_model != "schedule":
        raise ValueError(f"base_model 'spline' needs contact_model 'schedule', got {s.contact_model!r}")
    nbc = 3 if spline_base else 1  # columns of the contact-phase base splines: (x, z, pitch) or phi
    sps = BSpline(s.n_base_stance if spline_base else s.n_phi_stance, phases.takeoff)
    spl = BSpline(s.n_base_land if spline_base else s.n_phi_land, T - phases.touchdown)
    # the interior breakpoints of the latent and base splines in stance and landing
    knots = np.concatenate([sp.breakpoints, sps.breakpoints, phases.touchdown + spl.breakpoints])
    knots_s, knots_l = knots[(knots > 0) & (knots < phases.takeoff)], knots[(knots > phases.touchdown) & (knots < T)]
    if s.knot_nodes:  # contact nodes also at the breakpoints
        grid["stance"] = _merge_samples(grid["stance"], knots_s, np.zeros(0))
        grid["land"] = _merge_samples(grid["land"], knots_l, np.zeros(0))
    ts, tf, tl = grid["stance"], grid["flight"], grid["land"]
    nS, nF, nL = len(ts), len(tf), len(tl)
    nC = nS + nL

    # ---------------------------------------------------------------- variables
    Pfix = np.asarray(init["P"], float)
    Pfree = ca.MX.sym("P", s.n_control - 2, dlat)
    Pm = ca.vertcat(ca.DM(Pfix[:1]), Pfree, ca.DM(Pfix[-1:]))
    cs = ca.MX.sym("base_s" if spline_base else "phi_s", sps.n_control, nbc)
    cl = ca.MX.sym("base_l" if spline_base else "phi_l", spl.n_control, nbc)
    xL = ca.MX.sym("x_L")
    Lam = ca.MX.sym("lam", 6, nC)
    Limp = ca.MX.sym("lam_impact", 6)
    c_to, cd_to, L_to = ca.MX.sym("c_to", 2), ca.MX.sym("cd_to", 2), ca.MX.sym("L_to")
    pf = ca.MX.sym("pitch_flight", nF)
    vblocks = [("P", Pfree), ("phi_s", cs), ("phi_l", cl), ("x_L", xL), ("lam", Lam), ("lam_impact", Limp),
               ("c_to", c_to), ("cd_to", cd_to), ("L_to", L_to), ("pitch_flight", pf)]
    if s.time_scale:
        kt = ca.MX.sym("time_scale")
        vblocks.append(("time_scale", kt))
        ik, affine = 1 / kt, False
    else:
        kt, ik, affine = ca.MX(1.0), None, True
    w = ca.veccat(*[v for _, v in vblocks])

    def lat_rows(t):
        return _time_scaled(_spline_rows(sp, Pm, t), dlat, ik)  # (x, xd, xdd) in real time: 3d x K

    # torque rows: the active joints at the nodes, the force-free ones at the wrench samples, the
    # right side's mirror copies left out (:attr:`RowModel.unmirrored`)
    kept = rm.unmirrored
    torque_joints = {"torque": kept, "torque_free": np.intersect1d(rm.force_free, kept)}
    subsets = {"torque": torque_joints["torque"],
               "torque_free": np.searchsorted(rm.force_free, torque_joints["torque_free"])}
    g, jac, names = [], [], []
    terms = []  # (block, U, affine, selected rows of the block, first NLP row) for the exact Hessian

    def add(block: str, U: ca.MX, per_node: list[list[str]], affine: bool = affine):
        nr, layout = blocks[block]
        gb, jb = lifted_rows(nr, U, w, affine)
        idx, nm = _layout_indices(layout, nr.n_out, U.shape[1], per_node, subsets)
        if idx:
            gi, ji = select_rows(gb, jb, np.array(idx))
            terms.append((nr, U, affine, idx, len(names)))
            g.append(gi)
            jac.append(ji)
            names.extend(nm)

    def stance_base(t):
        return _time_scaled(_spline_rows(sps, cs, t), nbc, ik)  # (phi, phid, phidd) or (b, bd, bdd)

    def land_base(t):
        return _time_scaled(_spline_rows(spl, cl, t, phases.touchdown), nbc, ik)

    def anchored_inputs(t_stance, t_land):
        """(x, xd, xdd, base inputs, x_pin) at stance (toe at x = 0) and landing (x_L) times."""
        return ca.vertcat(ca.horzcat(lat_rows(t_stance), lat_rows(t_land)),
                          ca.horzcat(stance_base(t_stance), land_base(t_land)),
                          ca.horzcat(ca.DM.zeros(1, len(t_stance)), ca.repmat(xL, 1, len(t_land))))

    # contact nodes: stance (toe at x = 0), landing (toe at x_L)
    Uc = ca.vertcat(anchored_inputs(ts, tl), Lam)
    tw = np.zeros(0)  # wrench sample times (nominal)
    if s.contact_model not in ("schedule", "complementarity", "free"):
        raise ValueError(f"contact_model must be 'schedule', 'complementarity' or 'free', got {s.contact_model!r}")
    base_rows = ["dynamics"] + (["torque"] if s.torque_limits else []) + \
                (["heel_complementarity", "ball_complementarity"] if s.contact_model == "complementarity" else []) + \
                ["ball_height"] + (["toe_position", "heel_height"] if spline_base else ["heel_up"])
    per_node = [list(base_rows) for _ in range(nS)]
    for tk in tl:
        extra = (["zmp_polygon"] + (["com_polygon"] if tk >= phases.settle - 1e-9 else [])) if s.polygon else []
        per_node.append(base_rows + extra)
    add("contact_rows", Uc, per_node)
    if s.wrench_spacing > 0:  # the needed wrench in the loaded points' cone between the nodes
        tws, twl = (_between(tn, s.wrench_spacing) for tn in (ts, tl))
        # and just after each schedule switch, where the support's rear end jumps (heel -> ball):
        # on the 5 ms grid alone the centre of pressure was 1.3 cm behind the ball at heel-off
        # and at the interior breakpoints of the base and latent splines: their accelerations are
        # piecewise linear with kinks there, so the needed wrench has its extremes there (12 base
        # control points: fz fell from 0.07 at the samples to 0 at a knot between them)
        sw = phases.switch_samples()
        tws = _merge_samples(tws, np.concatenate([sw[sw < phases.takeoff], knots_s]), ts)
        twl = _merge_samples(twl, np.concatenate([sw[sw > phases.touchdown], knots_l]), tl)
        Uw = anchored_inputs(tws, twl)
        tw = np.concatenate([tws, twl])
        heel_w, ball_w = phases.loaded("heel", tw), phases.loaded("ball", tw)
        back = np.where(heel_w, "cop_heel", np.where(ball_w, "cop_ball", "cop_pad"))
        add("wrench_rows", Uw, [["wrench_normal", "wrench_friction", "cop_front", str(b)] +
                                (["torque_free"] if s.torque_limits else []) for b in back])

    # flight: takeoff state variables, pitch by the trapezoid rule on a fine grid, nodes
    tau_f = tf - phases.takeoff
    Xto = lat_rows(np.array([phases.takeoff]))
    add("takeoff_rows", ca.vertcat(Xto, stance_base(np.array([phases.takeoff])), c_to, cd_to, L_to, pf[0]),
        [["takeoff"]])
    nsub = max(1, int(s.flight_substeps))
    tau_fine = np.linspace(0.0, tau_f[-1], (nF - 1) * nsub + 1)
    Upd = ca.vertcat(lat_rows(phases.takeoff + tau_fine), ca.repmat(L_to, 1, len(tau_fine)))
    gpd, jpd = lifted_rows(blocks["pitch_rate_rows"][0], Upd, w, affine)
    pitch_row0 = len(names)
    A = ca.DM(cumulative_trapezoid_matrix(tau_fine)[:, ::nsub].T[1:])  # (nF - 1) x fine: int_0^tau_k pd ds
    B = ca.horzcat(-ca.DM.ones(nF - 1, 1), ca.DM.eye(nF - 1))  # p_k - p_0
    lin = ca.mtimes(B, pf)
    Apd = ca.mtimes(A, gpd)  # real time: the integral times k
    g.append(lin - kt * Apd)
    jac.append(ca.jacobian(lin, w) - kt * ca.mtimes(A, jpd) - ca.mtimes(Apd, ca.jacobian(kt, w)))
    names.extend(["pitch_integration"] * (nF - 1))
    Uf = ca.vertcat(lat_rows(tf), pf.T, ca.repmat(ca.vertcat(L_to, c_to, cd_to), 1, nF), kt * ca.DM(tau_f).T)
    add("flight_rows", Uf, [(["torque"] if s.torque_limits else []) + (["flight_clearance"] if 0 < k < nF - 1 else [])
                            for k in range(nF)])
    Utd = ca.vertcat(lat_rows(np.array([phases.touchdown])), land_base(np.array([phases.touchdown])), xL, pf[-1],
                     L_to, c_to, cd_to,
                     kt * float(tau_f[-1]), Limp)
    add("touchdown_rows", Utd, [["touchdown_position", "impact"]])

    # tube on a dense grid (the end points are fixed on the training path)
    n_tube = max(2, int(round(T / s.tube_spacing)) + 1)
    t_tube = np.linspace(0.0, T, n_tube)[1:-1]
    add("tube_rows", (ca.sparsify(ca.DM(sp.basis(t_tube, 0))) @ Pm).T, [["tube"] for _ in t_tube], affine=True)

    names_a = np.array(names)
    # torque rows in units of each joint's limit range
    row_scale = np.ones(len(names))
    for k, pos in torque_joints.items():
        sel = names_a == k
        row_scale[sel] = np.tile(1.0 / rm.torque_scale[pos], int(sel.sum()) // max(len(pos), 1))
    G_ = ca.vertcat(*g) * ca.DM(row_scale)
    J_ = ca.mtimes(ca.diag(ca.DM(row_scale)), ca.vertcat(*jac))
    bounds = {"dynamics": (0, 0), "torque": None, "torque_free": None,
              "heel_complementarity": (-np.inf, s.complementarity_eps),
              "ball_complementarity": (-np.inf, s.complementarity_eps), "ball_height": (-s.ball_tolerance, np.inf),
              "heel_up": (0, np.inf), "toe_position": (-s.foot_tolerance, s.foot_tolerance),
              "heel_height": (-s.contact_tolerance, np.inf), "zmp_polygon": (-np.inf, 0), "com_polygon": (-np.inf, 0),
              "takeoff": (0, 0), "pitch_integration": (0, 0), "flight_clearance": (0, np.inf),
              "touchdown_position": (0, 0), "impact": (0, 0), "tube": (-np.inf, s.tube),
              **{k: (0, np.inf) for k in ("wrench_normal", "wrench_friction", "cop_front", "cop_heel", "cop_ball",
                                          "cop_pad")}}
    lbg, ubg = np.zeros(len(names)), np.zeros(len(names))
    act = rm.active
    tmin, tmax = limits.tau_min[act] / rm.torque_scale, limits.tau_max[act] / rm.torque_scale
    for k, bnd in bounds.items():
        sel = names_a == k
        if k in torque_joints:
            pos = torque_joints[k]
            n = int(sel.sum()) // max(len(pos), 1)
            lbg[sel], ubg[sel] = np.tile(tmin[pos], n), np.tile(tmax[pos], n)
        elif sel.any():
            lbg[sel], ubg[sel] = bnd

    # objective weight p: p = 1 maximises the distance (Eq. 33, phase 2); p = 0 is phase 1, the
    # feasibility problem: the point satisfying every hard constraint closest to the initial fit
    # of the training path (squared deviation of the free latent control points)
    pw = ca.MX.sym("p_distance")
    dev = ca.sumsqr(Pfree - ca.DM(Pfix[1:-1])) / max(float(np.mean(np.square(Pfix))), 1e-12)
    f = pw * (-xL) + (1 - pw) * dev + 1e-4 * ca.sumsqr(Lam) + 1e-4 * ca.sumsqr(Limp)  # tiny force regularisation

    # bounds and initial guess
    lbx = -np.inf * np.ones(w.numel())
    ubx = np.inf * np.ones(w.numel())
    off, sizes = 0, {}
    for name, v in vblocks:
        sizes[name] = (off, off + v.numel())
        off += v.numel()
    for name in ("lam", "lam_impact"):
        lbx[slice(*sizes[name])] = 0.0
    if s.time_scale:
        lbx[slice(*sizes["time_scale"])], ubx[slice(*sizes["time_scale"])] = s.time_scale_bounds
    if s.contact_model == "schedule":
        # fixed contact sequence (:mod:`.phases`): an unloaded heel or ball has zero force; a
        # loaded ball stays on the ground and a loaded heel keeps the foot flat
        tc = np.concatenate([ts, tl])
        lam_ub = ubx[slice(*sizes["lam"])].reshape(nC, 6)  # view; node-major like Lam's columns
        heel, ball = phases.loaded("heel", tc), phases.loaded("ball", tc)
        lam_ub[~heel, 0:2] = 0.0
        lam_ub[~ball, 2:4] = 0.0
        imp_ub = ubx[slice(*sizes["lam_impact"])]
        imp_ub[0:2] = 0.0 if not phases.loaded("heel", np.array([phases.touchdown]))[0] else np.inf
        imp_ub[2:4] = 0.0 if not phases.loaded("ball", np.array([phases.touchdown]))[0] else np.inf
        if spline_base:  # a loaded heel stays on the ground
            ubg[names_a == "heel_height"] = np.where(heel, s.contact_tolerance, np.inf)
        else:
            ubg[names_a == "heel_up"] = np.where(heel, s.flat_foot_pitch, np.inf)
        lbg[names_a == "ball_height"] = np.where(ball, -s.contact_tolerance, -s.ball_tolerance)
        ubg[names_a == "ball_height"] = np.where(ball, s.contact_tolerance, np.inf)
    x0 = np.zeros(w.numel())
    x0[slice(*sizes["P"])] = Pfix[1:-1].ravel(order="F")
    x0[slice(*sizes["phi_s"])] = np.ravel(init["phi_s"], order="F")
    x0[slice(*sizes["phi_l"])] = np.ravel(init["phi_l"], order="F")
    x0[slice(*sizes["x_L"])] = init["x_L"]
    x0[slice(*sizes["lam"])] = init.get("lam", np.full(6 * nC, 1.0 / 12.0))
    x0[slice(*sizes["lam_impact"])] = 0.5
    fl = flight_guess(rm, sp, sps, Pfix, np.asarray(init["phi_s"], float).reshape(sps.n_control, nbc),
                      phases.takeoff, tau_fine, nsub)
    for name in ("c_to", "cd_to", "L_to", "pitch_flight"):
        x0[slice(*sizes[name])] = fl[name]
    if s.time_scale:
        x0[slice(*sizes["time_scale"])] = 1.0
    x0 = np.clip(x0, lbx, ubx)

    p0 = ca.MX.sym("p", 1)
    jac_g = ca.Function("jac_g", [w, p0], [G_, J_], ["x", "p"], ["g", "jac_g_x"])
    nlp = {"x": w, "p": pw, "f": f, "g": G_}
    opts = {"ipopt.max_iter": s.max_iter, "ipopt.tol": s.tol, "ipopt.print_level": s.print_level,
            "print_time": False, "ipopt.acceptable_tol": 1e-4, "ipopt.acceptable_iter": 10,
            "ipopt.constr_viol_tol": 1e-6, "ipopt.mu_strategy": "adaptive", "jac_g": jac_g,
            "calc_lam_p": False, "calc_lam_x": False}  # CasADi must not differentiate the compiled rows
    if warm_start:
        opts.update(WARM_START_OPTIONS)
    if exact:
        lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", len(names))
        H = lam_f * ca.hessian(f, w)[0]
        for nr, U, aff, idx, row0 in terms:  # each block's multipliers, in its own (unscaled) rows
            rows = np.arange(row0, row0 + len(idx))
            S = ca.DM.triplet(list(idx), rows.tolist(), row_scale[rows].tolist(), nr.n_out * U.shape[1], len(names))
            H = H + lifted_hessian(nr, U, w, ca.mtimes(S, lam_g), aff)[0]
        # pitch integration lin - k A pd: d2/dw2 of -k mu . pd with mu = A^T lam
        mu_pd = ca.mtimes(A.T, lam_g[pitch_row0:pitch_row0 + nF - 1])
        H_pd, grad_pd = lifted_hessian(blocks["pitch_rate_rows"][0], Upd, w, mu_pd, affine)
        dk = ca.jacobian(kt, w).T
        H = H - kt * H_pd - ca.mtimes(dk, grad_pd.T) - ca.mtimes(grad_pd, dk.T)
        hess_lag = ca.Function("hess_lag", [w, pw, lam_f, lam_g], [ca.triu(H)],
                               ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])
        opts["hess_lag"] = hess_lag
    else:
        opts["ipopt.hessian_approximation"] = "limited-memory"
    solver = ipopt_solver("broad_jump", nlp, opts)
    unpack = ca.Function("unpack", [w], [Pm, cs, cl, xL, Lam, Limp, c_to, cd_to, L_to, pf, kt],
                         ["w"], ["P", "phi_s", "phi_l", "x_L", "lam", "lam_impact", "c_to", "cd_to", "L_to",
                                 "pitch_flight", "time_scale"])
    build = time.perf_counter() - t0
    return JumpNLP(solver, x0, lbx, ubx, lbg, ubg, unpack, names, build,
                   {"grid": grid, "splines": (sp, sps, spl), "mass": mass, "wrench_times": tw,
                    "g_fun": ca.Function("g", [w], [G_]), "jac_fun": jac_g, "sizes": sizes,
                    "hess_fun": opts.get("hess_lag"), "f_fun": ca.Function("f", [w, pw], [f])})


def flight_guess(rm: RowModel, sp: BSpline, sps: BSpline, P: np.ndarray, base_s: np.ndarray, takeoff: float,
                 tau_fine: np.ndarray, nsub: int) -> dict[str, np.ndarray]:
    """Flight variables (takeoff COM, COM velocity, angular momentum, node pitch) of a guess
    whose stance base spline coefficients are ``base_s`` (foot pitch, or (x, z, pitch))."""
    t_to = np.array([takeoff])
    x = [sp.evaluate(P, t_to, k) for k in range(3)]
    f = [sps.evaluate(base_s.reshape(sps.n_control, -1), t_to, k).T for k in range(3)]
    if rm.base_model == "pinned":
        anch = anchored_function(rm.sym, rm.smap, rm.gpdm, rm.geom)
        b, bd, _ = (np.array(v).ravel() for v in anch(x[0].T, x[1].T, x[2].T, *f, 0.0))
    else:
        b, bd = f[0].ravel(), f[1].ravel()
    fns = flight_functions(rm.sym, rm.smap, rm.gpdm)
    c, cd, L = (np.array(v).ravel() for v in fns["momentum"](x[0].T, x[1].T, b, bd))
    Xf = [sp.evaluate(P, takeoff + tau_fine, k).T for k in range(3)]
    bb = ballistic_base(fns, *Xf, tau_fine, b, bd, x[0].T, x[1].T)
    return {"c_to": c, "cd_to": cd, "L_to": L, "pitch_flight": np.array(bb[0])[2, ::nsub]}
