"""The model kinds drape trains: one record each, which ``drape train``, ``drape evaluate`` and
``drape predict`` iterate (``datagen/cli/train.py``), so that a new model is one package plus one
record here (docs/architecture.md, "Adding a model kind").

A record names its parts by dotted path (``"package.module:attribute"``), imported when first used:
building the command line must not import torch. :func:`register` adds a record (a test's dummy
kind, or a plug-in); :func:`get_kind` answers an unknown name with one line that lists the kinds.
"""

from __future__ import annotations

import argparse
import importlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from datagen.errors import InputError


def resolve(target: Any) -> Any:
    """``target`` itself, or the object a ``"package.module:attribute"`` path names."""
    if not isinstance(target, str):
        return target
    module, _, name = target.partition(":")
    obj = importlib.import_module(module)
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj


@dataclass(frozen=True, kw_only=True)
class EvaluateRequest:
    """What ``drape evaluate`` asks of a kind's evaluation: the run directory, the store (None: the
    one it trained on), the split, the device, and the options some kinds read (the GNN: frames
    and a progress callback ``progress(done, total)``; the motion generator: repetitions and
    whether to measure generation)."""

    run: str
    data: str | None = None
    split: str = "test"
    device: str = "auto"
    max_frames: int | None = None
    repetitions: int = 20
    generation: bool = True
    progress: Callable[[int, int], None] | None = None


@dataclass(frozen=True, kw_only=True)
class ModelKind:
    """One model kind.

    Attributes:
        name: ``run.json``'s kind and the command's name (``drape train NAME``).
        help, description, epilog: the ``drape train NAME`` parser's texts.
        config: the config class (a :class:`~training.config.BaseConfig`), or its path.
        datamodule: ``(store, config) -> LightningDataModule`` (a
            :class:`~training.datamodule.StoreDataModule` subclass), or its path.
        module: the ``LightningModule`` class; ``module.from_data(config, datamodule)`` builds one.
        train: ``(data, out, config, *, device, resume, force) -> result`` (a dict with at least
            ``epochs``, ``seconds``, ``best`` and ``best_checkpoint``, see ``training.loop.fit``).
        evaluate: ``(EvaluateRequest) -> figures`` (JSON-able), or None: ``drape evaluate`` refuses.
        format_evaluation: ``figures -> text`` that ``drape evaluate`` prints.
        report: ``(result, config) -> text``: what ``drape train`` prints after training.
        arguments: ``(parser) -> None``: the kind's own options of ``drape train NAME``.
        overrides: ``(args) -> dict``: config fields those options set (None values: not given).
        predict: ``(run, data, sample) -> arrays`` for ``drape predict`` (``coarse``, ``detail``,
            ``truth`` [T, V, 3] m, ``error`` [T, V] m, ``garment``), or None.
        sample: what ``drape sample`` calls for the kind (or None), for the record.
    """

    name: str
    help: str
    config: Any
    datamodule: Any
    module: Any
    train: Any
    evaluate: Any = None
    format_evaluation: Any = None
    report: Any = None
    description: str | None = None
    epilog: str | None = None
    arguments: Callable[[argparse.ArgumentParser], None] | None = None
    overrides: Callable[[argparse.Namespace], dict[str, Any]] = field(default=lambda args: {})
    predict: Any = None
    sample: Any = None

    def part(self, name: str) -> Any:
        """The record's ``name`` part, imported (None where the kind has none)."""
        return resolve(getattr(self, name))

    def config_class(self) -> type:
        return self.part("config")


_KINDS: dict[str, ModelKind] = {}


def register(kind: ModelKind, *, replace: bool = False) -> ModelKind:
    """Add ``kind`` to the registry (``replace``: over one of the same name)."""
    if kind.name in _KINDS and not replace:
        raise ValueError(f"a model kind named {kind.name!r} is registered already")
    _KINDS[kind.name] = kind
    return kind


def unregister(name: str) -> None:
    _KINDS.pop(name, None)


def kinds() -> list[ModelKind]:
    """Every registered kind, in registration order."""
    return list(_KINDS.values())


def get_kind(name: str | None) -> ModelKind:
    """The record of kind ``name``; a name that is not registered is one line that lists the kinds."""
    if name not in _KINDS:
        known = ", ".join(_KINDS)
        what = "no model kind" if name is None else f"model kind {name!r}, which drape does not know"
        raise InputError(f"this run holds {what}; drape's kinds are {known}")
    return _KINDS[name]


# -- the three kinds of papers 000 and 001


def _gnn_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--ablation", default=None, help="a variant of paper 000 §5.3 (overrides the config)")


def _gnn_report(result: dict, config) -> str:
    return (f"trained {result['epochs']} epochs in {result['seconds']:.0f} s on {result['train_frames']} frames; best "
            f"validation detail error {result['best']:.2f} mm ({result['best_checkpoint']})")


def _gnn_evaluate(r: EvaluateRequest) -> dict:
    from training.gnn.run import evaluate_gnn

    return evaluate_gnn(r.run, data=r.data, split=r.split, max_frames=r.max_frames, device=r.device,
                        progress=r.progress)


def _motion_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--no-vertex-loss", action="store_true", help="train without L_V^B (Table 8's ablation)")


def _motion_report(result: dict, config) -> str:
    lines = [f"trained {result['epochs']} epochs in {result['seconds']:.0f} s on {result['train_segments']} segments; "
             f"best validation loss {result['best']:.4f} ({result['best_checkpoint']})"]
    if result["labels_without_training_segments"]:
        lines.append(f"warning: no training segments of {', '.join(result['labels_without_training_segments'])} (no "
                     "motion of the train split has that label): the generator has not learned them and "
                     "`drape sample motion` refuses them")
    return "\n".join(lines)


def _motion_evaluate(r: EvaluateRequest) -> dict:
    from training.motion.run import evaluate_motion

    return evaluate_motion(r.run, data=r.data, split=r.split, device=r.device, generation=r.generation,
                           repetitions=r.repetitions)


def _garment_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--garment", default=None, help="the garment type (overrides the config; default skirt)")
    p.add_argument("--zero-bos", action="store_true", help="a fixed zero BOS instead of the learned one (Table 9)")


def _garment_report(result: dict, config) -> str:
    return (f"trained {result['epochs']} epochs in {result['seconds']:.0f} s on {result['train_segments']} segments of "
            f"the {config.garment} template ({result['template_vertices']} vertices); best validation loss "
            f"{result['best']:.4f} ({result['best_checkpoint']})")


def _garment_evaluate(r: EvaluateRequest) -> dict:
    from training.garment.run import evaluate_garment

    return evaluate_garment(r.run, data=r.data, split=r.split, device=r.device)


GNN = register(ModelKind(
    name="gnn", help="paper 000's detail-aware GNN",
    config="training.gnn.config:GNNConfig", datamodule="training.gnn.data:GNNDataModule",
    module="training.gnn.module:GNNModule", train="training.gnn.run:train_gnn",
    evaluate=_gnn_evaluate, format_evaluation="training.gnn.run:format_evaluation", report=_gnn_report,
    arguments=_gnn_arguments, overrides=lambda args: {"ablation": args.ablation},
    predict="training.gnn.run:predict_sample"))

MOTION = register(ModelKind(
    name="motion", help="paper 001's Transformer-CVAE motion generator",
    description="Train paper 001's label-conditioned motion generator (§3.2) on a store's labelled 60-frame "
                "segments (pose, translation, label); the checkpoint is chosen on the val split's loss.",
    epilog="examples:\n  drape train motion --data motion.zarr --out runs/motion --device cuda\n"
           "  drape train motion --data motion.zarr --out runs/no-vertex --no-vertex-loss",
    config="training.motion.config:MotionConfig", datamodule="training.motion.data:MotionDataModule",
    module="training.motion.module:MotionModule", train="training.motion.run:train_motion",
    evaluate=_motion_evaluate, format_evaluation="training.motion.run:format_motion_evaluation",
    report=_motion_report, arguments=_motion_arguments,
    overrides=lambda args: {"vertex_loss": False if args.no_vertex_loss else None},
    sample="training.motion.run:sample_motions"))

GARMENT = register(ModelKind(
    name="garment", help="paper 001's garment regressor (one template)",
    description="Train paper 001's dynamic garment regressor (§3.3) for one garment type's template on a store's "
                "60-frame segments: a pose encoder and an autoregressive garment decoder with a learnable BOS "
                "(pretrained, then frozen), vertex and Laplacian losses.",
    epilog="examples:\n  drape train garment --data motion.zarr --garment skirt --out runs/skirt\n"
           "  drape train garment --data motion.zarr --garment skirt --out runs/skirt-zero-bos --zero-bos",
    config="training.garment.config:GarmentConfig", datamodule="training.garment.data:GarmentDataModule",
    module="training.garment.module:GarmentModule", train="training.garment.run:train_garment",
    evaluate=_garment_evaluate, format_evaluation="training.garment.run:format_garment_evaluation",
    report=_garment_report, arguments=_garment_arguments,
    overrides=lambda args: {"garment": args.garment, "bos": "zero" if args.zero_bos else None},
    sample="training.garment.run:dress_motion"))
