"""Humanoid standing broad jump (Kang & Park 2015, Sect. 4.2, Eq. 33-36) as a transcribed NLP.

Its modules, a folder per stage in the order the data flows:

1. :mod:`.robot` - the robot and its feet:

   * :mod:`.robot.robot_declaration` - the ``[robot]`` table of a problem file: model, mirror, feet, limits;
   * :mod:`.robot.sagittal_base` - the sagittal base (x, z, pitch) and its free-flyer q, v, a;
   * :mod:`.robot.feet` - the feet's contact points (heel, ball, toe tip, toe pad) and their forces;
   * :mod:`.robot.zmp` - zero-moment point from the centroidal momentum rate;
   * :mod:`.robot.support_polygon` - the support polygon's inequalities (Eq. 35-36);
   * :mod:`.robot.torque_limits` - tau_min, tau_max of Eq. 34 from the training motion;
   * :mod:`.robot.jump_robot` - what the row families know of the robot (models, feet, limits, mass);

2. :mod:`.demonstration` - the training jump:

   * :mod:`.demonstration.training` - the symmetric training jump (37 learned DOF) on the
     symmetrised CMU humanoid (:mod:`latentoc.robots.cmu_humanoid`);
   * :mod:`.demonstration.planted` - its feet planted before the GPDM learns it;

3. :mod:`.schedule` - when and along what:

   * :mod:`.schedule.phases` - stance / flight / landing timing, the contact schedule, the knots, the
     NLP's nodes and samples;
   * :mod:`.schedule.path` - the spline a method solves along (latent path, residual, joints);

4. :mod:`.closure` - what follows from the path by construction:

   * :mod:`.closure.planted_legs` - the planted foot: the legs' dependent joints and the base in contact;
   * :mod:`.closure.ballistic` - the ballistic flight's momentum, pitch rate and base;

5. :mod:`.rows` - the row families' robot blocks, one per module (contact, flight, transitions,
   tube_rows, joint_limits);

6. :mod:`.transcription` - the NLP:

   * :mod:`.transcription.variables` - the decision vector's named blocks;
   * :mod:`.transcription.selection` - which rows and samples enter the NLP;
   * :mod:`.transcription.wiring` - how a row family's nodes see the decision vector;
   * :mod:`.transcription.nlp` - the NLP: families on nodes and samples, bounds, objective;

7. :mod:`.solve` - the solve:

   * :mod:`.solve.initial_point` - the training start in the NLP's variables;
   * :mod:`.solve.consistent_path` - its path moved so that the planted foot's base is physical;
   * :mod:`.solve.exchange` - the rows the 1 kHz checks add;
   * :mod:`.solve.warm` - a point carried into a larger NLP;
   * :mod:`.solve.solve` - phase 1, phase 2 and the exchange's rounds;

8. :mod:`.check` - the solved motion checked:

   * :mod:`.check.export` - the solved motion on a 1 kHz grid;
   * :mod:`.check.verify` - its 1 kHz recomputation with numeric Pinocchio;

and, for the problem file: :mod:`.settings` (the transcription's settings), :mod:`.problem`
(schema, set-up and solve of a problem file) and :mod:`.kind` (the ``"broad-jump"`` kind,
:data:`latentoc.problem.kinds.KINDS`).
"""
