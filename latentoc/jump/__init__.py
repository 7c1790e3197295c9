"""Humanoid standing broad jump (Kang & Park 2015, Sect. 4.2, Eq. 33-36) as a transcribed NLP.

Modules, one concept each:

* :mod:`.training` - symmetric CMU model and the symmetric training jump (37 learned DOF);
* :mod:`.base` - the sagittal base (x, z, pitch) and its free-flyer q, v, a;
* :mod:`.contact` - foot contact points, the ball-pinned foot anchoring, wrench constraints;
* :mod:`.support_polygon` - A_S, b_S of Eq. 35-36;
* :mod:`.zmp` - zero-moment point from the centroidal momentum rate;
* :mod:`.phases` - stance / flight / landing timing and the node grid;
* :mod:`.torque_limits` - tau_min, tau_max of Eq. 34 from the training motion;
* :mod:`.transcription` - the NLP;
* :mod:`.problem` - settings, set-up and solve of a problem file;
* :mod:`.kind` - the ``"broad-jump"`` kind (:data:`latentoc.kinds.KINDS`);
* :mod:`.verify` - 1 kHz recomputation with numeric Pinocchio.
"""
