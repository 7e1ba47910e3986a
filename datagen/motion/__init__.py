"""Motions: rotation conventions, labelled procedural motions, and AMASS/BVH readers."""
