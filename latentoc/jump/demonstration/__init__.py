"""The training jump: :mod:`.training` (the symmetric jump the GPDM learns) and :mod:`.planted`
(its feet planted before learning)."""
