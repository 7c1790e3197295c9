"""Humanoid standing broad jump (Kang & Park 2015, Sect. 4.2, Eq. 33-36) as a transcribed NLP.

Modules, one concept each:

* :mod:`.training` - symmetric CMU model and the symmetric training jump (37 learned DOF);
* :mod:`.base` - the sagittal base (x, z, pitch) and its free-flyer q, v, a;
* :mod:`.contact` - the feet's contact points (heel, ball, toe tip, toe pad) and their forces;
* :mod:`.closure` - the planted foot by construction: the legs' dependent joints and the base in contact;
* :mod:`.zmp` - zero-moment point from the centroidal momentum rate;
* :mod:`.phases` - stance / flight / landing timing and the contact schedule;
* :mod:`.torque_limits` - tau_min, tau_max of Eq. 34 from the training motion;
* :mod:`.flight` - the ballistic flight's momentum, pitch rate and base (for the start and export);
* :mod:`.rows` - the row families' robot blocks;
* :mod:`.selection` - which rows and samples enter the NLP; :mod:`.nlp` - the NLP;
* :mod:`.start` - the training start, :mod:`.consistent_start` - its path moved so that the planted
  foot's base is physical; :mod:`.warm` - a point carried into a larger NLP;
* :mod:`.solve` - phase 1, phase 2 and the exchange's rounds (:mod:`.exchange`);
* :mod:`.export` - the solved motion on a 1 kHz grid;
* :mod:`.problem` - settings, set-up and solve of a problem file;
* :mod:`.kind` - the ``"broad-jump"`` kind (:data:`latentoc.problem.kinds.KINDS`);
* :mod:`.verify` - 1 kHz recomputation with numeric Pinocchio.
"""
