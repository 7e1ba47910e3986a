"""drape's data generation side: bodies, motions, garments, the cloth simulator and the store."""

__version__ = "0.1.0"
