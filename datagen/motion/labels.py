"""drape's motion label vocabulary: label names and their integer classes.

The procedural library (:mod:`datagen.motion.library`) generates every label in :data:`LABELS`;
readers of mocap archives map file names onto label names with a user-given mapping file. A label's
integer class is its position in :data:`LABELS`; names a mapping file adds that drape does not
generate follow in the order the file first names them (:func:`label_vocabulary`).
"""

from __future__ import annotations

from datagen.errors import InputError

__all__ = ["LABELS", "label_index", "label_vocabulary"]

LABELS: tuple[str, ...] = (
    "walk",
    "run",
    "jump",
    "squat",
    "lunge",
    "kick",
    "wave",
    "raise_arms",
    "arm_circles",
    "torso_twist",
    "bend_forward",
    "side_bend",
    "sit_stand",
    "turn_in_place",
    "box",
    "dance_sway",
    "dance_disco",
)
"""The labels drape generates procedurally, in class order (class = index)."""


def label_vocabulary(extra: tuple[str, ...] | list[str] = ()) -> tuple[str, ...]:
    """:data:`LABELS` followed by the names in ``extra`` that are not already in it (first-seen order)."""
    out = list(LABELS)
    for name in extra:
        if not isinstance(name, str) or not name:
            raise InputError(f"a label name must be a non-empty string, got {name!r}")
        if name not in out:
            out.append(name)
    return tuple(out)


def label_index(name: str, vocabulary: tuple[str, ...] = LABELS) -> int:
    """The integer class of ``name`` in ``vocabulary``; an unknown name raises with the known ones."""
    try:
        return vocabulary.index(name)
    except ValueError:
        raise InputError(
            f"unknown motion label {name!r}; known labels: {', '.join(vocabulary)} "
            "(`drape motion list` shows them with their parameters)"
        ) from None
