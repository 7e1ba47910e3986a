"""Versioned layouts of what drape writes to disk.

``schemas.body_file`` describes the SMPL-format body files (read by ``datagen.body.io``); the dataset store's schema joins it
when the store is built.
"""
