"""Export and look: animated USD files, pictures and clips of samples, from a store, a
``drape simulate`` result or a model's prediction.

- ``usd``: :func:`~datagen.export.usd.write_animation_usd`, the writer of body + garment
  animations (plain arrays in; optional UsdSkel rig), the stage conventions shared with the motion
  exporter, and :func:`~datagen.export.usd.usd_validation_errors`.
- ``animation``: :class:`~datagen.export.animation.Animation`, the arrays of one scene, and the
  loaders that make one from a store sample or an ``.npz`` (``drape simulate`` output or plain
  arrays).
- ``preview``: offscreen renders (matplotlib, CPU) of frames to PNG and of clips to GIF/MP4,
  optionally coloured by stretch, distance to the body or prediction error.
- ``files``: output-path checks and write-to-temporary-then-rename.
- ``cli``: ``drape export usd`` and ``drape preview``.

Nothing heavy is imported here: usd-core, matplotlib and imageio are imported when used. See
``docs/export.md``.
"""
