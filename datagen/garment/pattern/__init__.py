"""Garments from sewing patterns: the pattern model, GarmentCode's JSON, flat meshing, placement.

:mod:`~datagen.garment.pattern.model` holds the records (panels, edges, stitches);
:mod:`~datagen.garment.pattern.spec` reads and writes GarmentCode's specification JSON;
:mod:`~datagen.garment.pattern.mesh` triangulates the flat panels; ``placement`` puts them around
the body; ``svg`` draws them; ``programs`` builds patterns from design parameters fitted to a body.
docs/patterns.md is the reference.
"""
