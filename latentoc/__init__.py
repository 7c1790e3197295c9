"""latentoc: motion optimization in a learned GPDM latent space (Kang & Park 2015)."""

__version__ = "0.1.0"
