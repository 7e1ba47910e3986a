"""The one way drape opens a checkpoint: what it opens is checked, and a refusal says which check failed.

- :func:`read_checkpoint`: the file is there, readable and whole (a truncated or overwritten file is
  "damaged", not a traceback of torch's unpickler or zip reader).
- :func:`load_module`: the checkpoint holds this model kind (its hyper-parameters build this module,
  its weights have this module's names) with this config's shapes.
- :func:`check_resume`: the resume checkpoint of a run fits the module the run's config builds, before
  Lightning restores it and before anything of the run directory is changed.
- :func:`run_store`: the store a run names is still there (or the one ``--data`` gives).
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from datagen.errors import InputError

log = logging.getLogger(__name__)


def read_checkpoint(path: str | Path) -> dict[str, Any]:
    """The checkpoint dict at ``path`` (on the CPU), or an :class:`InputError` saying it is missing or damaged."""
    import torch

    path = Path(path)
    if not path.is_file():
        raise InputError(f"checkpoint {path} does not exist; train the run first (or give its run directory)")
    try:
        ckpt = torch.load(path, map_location="cpu", weights_only=False)
    except Exception as exc:  # noqa: BLE001 - torch's unpickler and zip reader raise many kinds
        log.debug("reading %s failed", path, exc_info=True)
        first = (str(exc).strip().splitlines() or [type(exc).__name__])[0].split(". ")[0][:160]
        raise InputError(f"checkpoint {path} is damaged: it cannot be read ({type(exc).__name__}: {first}; "
                         f"{path.stat().st_size:,} bytes, truncated or overwritten?). Restore it from a copy, or "
                         "train the run again with --force") from None
    if not isinstance(ckpt, dict) or not isinstance(ckpt.get("state_dict"), dict):
        raise InputError(f"checkpoint {path} is damaged: it is not a drape (Lightning) checkpoint (no state_dict); "
                         "restore it from a copy, or train the run again with --force")
    return ckpt


def _shape_problems(expected: dict, found: dict) -> tuple[list[str], list[str], list[str]]:
    """(missing names, unexpected names, 'name: shape against shape') between two state dicts."""
    missing = sorted(set(expected) - set(found))
    unexpected = sorted(set(found) - set(expected))
    shapes = [f"{k}: {tuple(found[k].shape)} in the checkpoint, {tuple(expected[k].shape)} in this config's model"
              for k in sorted(set(expected) & set(found))
              if hasattr(found[k], "shape") and tuple(found[k].shape) != tuple(expected[k].shape)]
    return missing, unexpected, shapes


def _mismatch(path: Path, model: str, expected: dict, found: dict) -> str | None:
    missing, unexpected, shapes = _shape_problems(expected, found)
    shared = len(set(expected) & set(found))
    if shared < max(1, len(expected) // 2):
        return (f"checkpoint {path} belongs to another model, not {model}: {shared} of its {len(found)} weights "
                f"have {model}'s names (e.g. {', '.join((unexpected or missing)[:2])}); give a run of {model}")
    if missing or unexpected or shapes:
        detail = shapes[:1] or [f"{len(missing)} weight(s) missing (e.g. {missing[0]})" if missing else
                                f"{len(unexpected)} weight(s) this config has not (e.g. {unexpected[0]})"]
        return (f"checkpoint {path} is {model} with other shapes than this config's ({detail[0]}); resume or "
                "evaluate with the config it was trained with, or train a new run with --force")
    return None


def load_module(module_class, path: str | Path, model: str, **kwargs):
    """``module_class`` (a ``LightningModule``) restored from the checkpoint at ``path`` on the CPU, or one
    :class:`InputError`: damaged, another model (``model`` names the expected one), other shapes.

    Args:
        module_class: the module class of the run's kind.
        path: the checkpoint file.
        model: the expected model in words (``"paper 000's GNN"``).
        kwargs: what ``load_from_checkpoint`` needs beyond the hyper-parameters (e.g. the body).
    """
    path = Path(path)
    ckpt = read_checkpoint(path)
    hyper = ckpt.get("hyper_parameters")
    try:
        module = module_class(**{**(hyper or {}), **kwargs})  # as Lightning's load_from_checkpoint builds it
    except TypeError as exc:
        raise InputError(f"checkpoint {path} belongs to another model, not {model}: its hyper-parameters do not "
                         f"build one ({exc}); give a run of {model}") from None
    except InputError as exc:
        raise InputError(f"checkpoint {path} does not fit {model}: {exc}") from None
    module.on_load_checkpoint(ckpt)  # what Lightning's load_from_checkpoint does first (e.g. renames old weights)
    problem = _mismatch(path, model, module.state_dict(), ckpt["state_dict"])
    if problem:
        raise InputError(problem)
    module.load_state_dict(ckpt["state_dict"])
    module.eval()
    return module


def check_resume(path: str | Path, module, model: str = "this run's model") -> None:
    """Refuse (:class:`InputError`) to resume from ``path`` when it is damaged or does not fit
    ``module`` (the model the run's config builds), before Lightning restores it."""
    ckpt = read_checkpoint(path)
    module.on_load_checkpoint(ckpt)  # Lightning calls it before restoring the weights (changes ckpt only)
    problem = _mismatch(Path(path), model, module.state_dict(), ckpt["state_dict"])
    if problem:
        raise InputError("--resume: " + problem)
    for key in ("optimizer_states", "epoch", "global_step"):
        if key not in ckpt:
            raise InputError(f"--resume: checkpoint {path} has no {key} (it holds weights only, not a run's state); "
                             "resume from checkpoints/last.ckpt, or train a new run with --force")


def run_store(meta: dict, run: str | Path, data: str | Path | None = None):
    """The store of a run: ``data`` when given, else the one its ``run.json`` names, opened; one line
    when the named store is no longer there."""
    from datagen.store import open_store

    if data is not None:
        return open_store(data)
    named = (meta.get("store") or {}).get("path")
    if not named:
        raise InputError(f"{run}'s run.json names no store; give the store with --data")
    if not Path(named).exists():
        raise InputError(f"the store run {run} was trained on is no longer at {named} (moved or deleted); give "
                         "where it is now with --data STORE")
    return open_store(named)
