"""The latent motion: the B-spline path (Eq. 20, 23-25) and the GP layer on it (Eq. 18-19, 26-28)."""
from latentoc.latent.gp_layer import GPLayer, IdentityLayer, LatentMotion, Layer
from latentoc.latent.residual_layer import ResidualLayer

__all__ = ["GPLayer", "IdentityLayer", "Layer", "LatentMotion", "ResidualLayer"]
