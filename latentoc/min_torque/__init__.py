"""The ``"latent-min-torque"`` kind: the minimum-torque motion of a fixed-base robot (Sect. 4.1).

One module per concept: :mod:`.problem` (the problem file's keys and checks), :mod:`.settings`
(the transcription), :mod:`.objectives`, :mod:`.limits` and :mod:`.goal` (the running cost, the
hard limits, an end-effector goal), :mod:`.training` (the training frames and the GPDM),
:mod:`.nlp` (Eq. 22 on the derivative layer), :mod:`.exchange` (constraint points until the
1 kHz grid holds), :mod:`.solve`, :mod:`.export` (the result) and :mod:`.kind` (the Kind).
"""
