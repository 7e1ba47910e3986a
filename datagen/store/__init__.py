"""The dataset store: a zarr v3 directory laid out by :mod:`schemas.dataset`.

- :class:`StoreWriter` (``writer``): create or reopen a store, stage samples and static groups
  crash-safely from any number of processes, then :meth:`~StoreWriter.pack` it in one (``pack``);
  what is staged is checked against the schema first (``checks``: :func:`check_sample`,
  :func:`check_static`).
- :func:`open_store` (``reader``): samples, frames, segments, garment meshes, body and fit models.
- :func:`validate` (``validation``): every problem of a packed store, as messages; its check of
  the shard files against their recorded digests (``integrity``) also guards every read, which
  raises :class:`DamagedStoreError` for a missing or changed shard.
- :func:`store_info` / :func:`format_store_info` (``info``): counts, sizes on disk, failures
  (plots of a store: :func:`datagen.export.plots.plot_store_info`).

The names below are loaded on first use (PEP 562), so ``from datagen.store import open_store``
loads the reader alone: a trainer's DataLoader workers never import the writer (``fcntl``),
the validator or the summary. ``tests/store/test_store.py`` checks it.

See ``docs/store.md``.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "DatasetStore": "reader", "open_store": "reader",
    "StorageError": "layout", "DamagedStoreError": "integrity",
    "SAMPLE_ARRAYS": "checks", "SAMPLE_SCALARS": "checks", "StoreWriter": "writer", "check_sample": "checks",
    "check_static": "checks",
    "validate": "validation",
    "format_store_info": "info", "store_info": "info",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'datagen.store' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"datagen.store.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
