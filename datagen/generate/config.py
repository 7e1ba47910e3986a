"""The dataset configuration of ``drape generate``: garments x bodies x motions per split, the
simulator's settings, and the presets.

A config file (TOML or YAML) has the fields of :class:`DatasetConfig` at the top level and one
table per split::

    seed = 0
    frames = 60                     # recorded frames per sample (motion frames)
    [simulation]                    # datagen.sim.scene.RunConfig, and batch_size
    ramp = 1.0
    [simulation.solver]             # datagen.sim.solver.SolverConfig
    substeps = 10
    [train]
    garments = ["tshirt:0", "pants:0"]      # type:seed
    bodies = ["regular"]                    # thin | regular | fat | seed:N
    motions = ["walk:0", "dance_sway:0"]    # label:seed
    [val] ...
    [test] ...

Every split's scenes are the product garments x bodies x motions. Splits share no garment
(type, seed), body or motion unless ``split_disjoint`` says otherwise (paper 001 keeps one garment
template per type and the mean body, and splits by motion only).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path

from datagen.config import load_config
from datagen.errors import ConfigError
from datagen.garment.registry import EDGE_LENGTH_RANGE
from datagen.sim.scene import RunConfig

BODY_PRESETS = ("thin", "regular", "fat")
FIT_FACTORS = 3
"""Factors of the fit attribute α (paper 000: 3)."""
DISJOINT_KINDS = ("garments", "bodies", "motions")


@dataclass(frozen=True, kw_only=True)
class SplitConfig:
    """One split: its scenes are every garment on every body doing every motion.

    Attributes:
        garments: ``type:seed`` (``drape garment list``).
        bodies: a preset (thin, regular, fat) or ``seed:N`` (a sampled shape).
        motions: ``label:seed`` (``drape motion list``).
    """

    garments: tuple[str, ...] = ()
    bodies: tuple[str, ...] = ()
    motions: tuple[str, ...] = ()

    @property
    def scene_count(self) -> int:
        return len(self.garments) * len(self.bodies) * len(self.motions)


@dataclass(frozen=True, kw_only=True)
class SimulationConfig(RunConfig):
    """How every scene is simulated: the simulator's own :class:`~datagen.sim.scene.RunConfig`
    (its phases, ``solver`` settings and failure ``thresholds``, with the simulator's defaults and
    limits), and how many scenes share a model.

    Attributes:
        batch_size: scenes simulated together in one model (same frame count); it only spreads the
            work (a scene's result does not depend on its batch), so it is not part of a store's
            identity.
    """

    batch_size: int = field(default=8, metadata={"min": 1, "max": 4096})


@dataclass(frozen=True, kw_only=True)
class DatasetConfig:
    """A dataset: what to simulate and how (SI units).

    Attributes:
        seed: the dataset seed (the fit model's subsampling and factor analysis).
        fps: frame rate of the motions [1/s].
        frames: recorded frames per sample.
        segment_length: frames per segment for paper 001's sequence models.
        garment_edge_length: target edge length of the garments [m] (None: each type's default).
        fit_attribute: fit paper 000's fit attribute α (a factor analysis over the training split's
            garment-body pairs, which needs more than 3 of them); paper 001's models never use it.
        split_disjoint: what the splits must not share.
        simulation: simulator settings.
        train, val, test: the splits.
    """

    seed: int = 0
    fps: float = field(default=30.0, metadata={"min": 1.0, "max": 240.0})
    frames: int = field(default=60, metadata={"min": 1, "max": 100000})
    segment_length: int = field(default=60, metadata={"min": 1, "max": 100000})
    garment_edge_length: float | None = field(default=None, metadata={"min": EDGE_LENGTH_RANGE[0],
                                                                      "max": EDGE_LENGTH_RANGE[1]})
    fit_attribute: bool = True
    split_disjoint: tuple[str, ...] = DISJOINT_KINDS
    simulation: SimulationConfig = field(default_factory=SimulationConfig)
    train: SplitConfig = field(default_factory=SplitConfig)
    val: SplitConfig = field(default_factory=SplitConfig)
    test: SplitConfig = field(default_factory=SplitConfig)

    def __post_init__(self):
        check_dataset_config(self)

    @property
    def splits(self) -> dict[str, SplitConfig]:
        return {"train": self.train, "val": self.val, "test": self.test}

    def as_dict(self) -> dict:
        return _plain(dataclasses.asdict(self))


def _plain(x):
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    return x


def _parse_pair(text: str, what: str, names: tuple[str, ...]) -> tuple[str, int]:
    name, sep, seed = text.partition(":")
    if not sep or not seed.lstrip("-").isdigit():
        raise ConfigError(f"{what} {text!r} must be written name:seed, e.g. '{names[0]}:0'")
    if seed.startswith("-"):
        raise ConfigError(f"{what} {text!r}: the seed must be 0 or more")
    if name not in names:
        raise ConfigError(f"unknown {what} {name!r} in {text!r}; choose from: {', '.join(names)}")
    return name, int(seed)


def parse_garment(text: str) -> tuple[str, int]:
    from datagen.garment.types import GARMENT_TYPES

    return _parse_pair(text, "garment", tuple(GARMENT_TYPES))


def parse_motion(text: str) -> tuple[str, int]:
    from datagen.motion.labels import LABELS

    return _parse_pair(text, "motion", tuple(LABELS))


def parse_body(text: str) -> tuple[str, int | None]:
    if text in BODY_PRESETS:
        return text, None
    kind, sep, seed = text.partition(":")
    if kind == "seed" and sep and seed.isdigit():
        return "seed", int(seed)
    raise ConfigError(f"body {text!r} must be one of {', '.join(BODY_PRESETS)} or seed:N (a sampled shape)")


def check_dataset_config(c: DatasetConfig) -> None:
    """Names that exist, no repeats, non-empty splits where needed, disjoint splits."""
    unknown = set(c.split_disjoint) - set(DISJOINT_KINDS)
    if unknown:
        raise ConfigError(f"split_disjoint has {sorted(unknown)}; allowed: {', '.join(DISJOINT_KINDS)}")
    if not c.train.scene_count:
        raise ConfigError("the train split has no scenes: give it at least one garment, body and motion")
    if c.frames < c.segment_length:
        raise ConfigError(f"frames ({c.frames}) is shorter than segment_length ({c.segment_length}): no sample "
                          "would make a segment")
    seen: dict[str, dict[str, str]] = {k: {} for k in DISJOINT_KINDS}
    for split, s in c.splits.items():
        for kind, items, parse in (("garments", s.garments, parse_garment), ("bodies", s.bodies, parse_body),
                                   ("motions", s.motions, parse_motion)):
            if len(set(items)) != len(items):
                raise ConfigError(f"{split}.{kind} lists an entry twice: {list(items)}")
            for item in items:
                parse(item)
                other = seen[kind].get(item)
                if other and other != split and kind in c.split_disjoint:
                    raise ConfigError(f"{item!r} is in both {other}.{kind} and {split}.{kind}; splits must not share "
                                      f"{kind} (or drop '{kind}' from split_disjoint)")
                seen[kind].setdefault(item, split)
    if c.fit_attribute:
        pairs = len({(g, b) for g in c.train.garments for b in c.train.bodies})
        if pairs <= FIT_FACTORS:
            raise ConfigError(f"the fit attribute (a factor analysis with {FIT_FACTORS} factors) needs more than "
                              f"{FIT_FACTORS} garment-body pairs in the train split, which has {pairs}; add garments "
                              "or bodies to it, or set fit_attribute = false (paper 001's models do not use α)")


PRESETS: dict[str, dict] = {
    # a few minutes on 2 CPU cores: coarse garments, one 60-frame segment each, three bodies
    "tiny": {
        "seed": 0, "frames": 60, "segment_length": 60, "garment_edge_length": 0.035,
        "simulation": {"settle_rest": 10, "lead_in": 0.5, "settle_pose": 5, "ramp": 0.5, "batch_size": 8},
        "train": {"garments": ["tshirt:0", "pants:0"], "bodies": ["regular", "seed:1"], "motions": ["walk:0"]},
        "val": {"garments": ["skirt:1"], "bodies": ["thin"], "motions": ["wave:1"]},
        "test": {"garments": ["dress:2"], "bodies": ["fat"], "motions": ["squat:2"]},
    },
    # a GPU in a few minutes: six garment types on two bodies doing four motions for training,
    # 56 scenes of 60 frames in one batch
    "small": {
        "seed": 0, "frames": 60, "segment_length": 60,
        "simulation": {"batch_size": 64},
        "train": {"garments": ["tshirt:0", "tank_top:0", "dress:0", "skirt:0", "pants:0", "shorts:0"],
                  "bodies": ["regular", "seed:1"], "motions": ["walk:0", "dance_sway:0", "squat:0", "wave:0"]},
        "val": {"garments": ["tshirt:7", "skirt:7"], "bodies": ["seed:7"], "motions": ["walk:7", "box:7"]},
        "test": {"garments": ["dress:9", "pants:9"], "bodies": ["fat"], "motions": ["walk:9", "dance_disco:9"]},
    },
    # paper 000 §5.1: 17 garments, 6 bodies, ~2,900 poses for training; 7 garments, 3 bodies, ~400 poses
    # for testing; 3 garments, 2 bodies, ~100 poses for validation (meant for a GPU)
    "paper-gnn": {
        "seed": 0, "frames": 60, "segment_length": 60,
        "simulation": {"batch_size": 64},
        "train": {
            "garments": [f"{t}:{s}" for t, s in (("tshirt", 0), ("tshirt", 1), ("long_sleeve_shirt", 0), ("long_sleeve_shirt", 1),
                                                 ("tank_top", 0), ("jacket", 0), ("coat", 0), ("dress", 0),
                                                 ("dress", 1), ("skirt", 0), ("skirt", 1), ("flared_skirt", 0),
                                                 ("pants", 0), ("pants", 1), ("shorts", 0), ("shorts", 1),
                                                 ("tank_top", 1))],
            "bodies": ["regular", "thin", "fat", "seed:1", "seed:2", "seed:3"],
            "motions": [f"{m}:0" for m in ("walk", "run", "jump", "squat", "lunge", "kick", "wave", "raise_arms",
                                           "arm_circles", "torso_twist", "bend_forward", "side_bend", "sit_stand",
                                           "turn_in_place", "box", "dance_sway", "dance_disco")]
            + [f"{m}:1" for m in ("walk", "run", "jump", "squat", "lunge", "kick", "wave", "raise_arms",
                                  "arm_circles", "torso_twist", "bend_forward", "side_bend", "sit_stand",
                                  "turn_in_place", "box", "dance_sway", "dance_disco")]
            + [f"{m}:2" for m in ("walk", "run", "dance_sway", "dance_disco", "box", "wave", "squat", "kick",
                                  "lunge", "jump", "sit_stand", "torso_twist", "arm_circles", "side_bend")],
        },
        "val": {"garments": ["tshirt:7", "dress:7", "pants:7"], "bodies": ["seed:7", "seed:8"],
                "motions": ["walk:7", "dance_disco:7"]},
        "test": {"garments": ["tshirt:9", "long_sleeve_shirt:9", "jacket:9", "coat:9", "dress:9", "skirt:9", "pants:9"],
                 "bodies": ["seed:10", "seed:11", "seed:12"],
                 "motions": [f"{m}:9" for m in ("walk", "run", "squat", "wave", "box", "dance_sway", "dance_disco")]},
    },
    # paper 001 §4.1: one template per garment type (skirt, T-shirt, pants) on the mean body, motions
    # of every label cut into T = 60 segments; split by motion only
    "paper-motion": {
        "seed": 0, "frames": 240, "segment_length": 60, "split_disjoint": ["motions"], "fit_attribute": False,
        "simulation": {"batch_size": 64},
        "train": {"garments": ["skirt:0", "tshirt:0", "pants:0"], "bodies": ["regular"],
                  "motions": [f"{m}:{s}" for s in range(4) for m in (
                      "walk", "run", "jump", "squat", "lunge", "kick", "wave", "raise_arms", "arm_circles",
                      "torso_twist", "bend_forward", "side_bend", "sit_stand", "turn_in_place", "box", "dance_sway",
                      "dance_disco")]},
        "val": {"garments": ["skirt:0", "tshirt:0", "pants:0"], "bodies": ["regular"],
                "motions": [f"{m}:8" for m in ("walk", "squat", "wave", "box", "dance_sway", "dance_disco")]},
        "test": {"garments": ["skirt:0", "tshirt:0", "pants:0"], "bodies": ["regular"],
                 "motions": [f"{m}:9" for m in ("walk", "run", "jump", "squat", "kick", "wave", "arm_circles", "box",
                                                "dance_sway", "dance_disco")]},
    },
}


def resolve_config(path: str | Path | None = None, preset: str | None = None) -> DatasetConfig:
    """The config from a file, or a preset (default ``tiny``); not both."""
    if path is not None and preset is not None:
        raise ConfigError("give a config file or --preset, not both")
    if path is not None:
        return load_config(DatasetConfig, path)
    name = preset or "tiny"
    if name not in PRESETS:
        raise ConfigError(f"unknown preset {name!r}; presets: {', '.join(PRESETS)}")
    return load_config(DatasetConfig, PRESETS[name])
