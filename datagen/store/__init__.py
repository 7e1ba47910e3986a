"""The dataset store: a zarr v3 directory laid out by :mod:`schemas.dataset`.

- :class:`StoreWriter` (``writer``): create or reopen a store, stage samples and static groups
  crash-safely from any number of processes, then :meth:`~StoreWriter.pack` it in one.
- :func:`open_store` (``reader``): samples, frames, segments, garment meshes, body and fit models.
- :func:`validate` (``validate``): every problem of a packed store, as messages.
- :func:`store_info` / :func:`format_store_info` (``info``): counts, sizes on disk, failures;
  :func:`plot_store_info`: the same and the fit attribute and body shapes as PNG plots.

See ``docs/store.md``.
"""

from datagen.store.info import format_store_info, plot_store_info, store_info
from datagen.store.layout import StorageError
from datagen.store.reader import DatasetStore, open_store
from datagen.store.validate import validate
from datagen.store.writer import SAMPLE_ARRAYS, SAMPLE_SCALARS, StoreWriter, check_sample, check_static

__all__ = [
    "SAMPLE_ARRAYS",
    "SAMPLE_SCALARS",
    "DatasetStore",
    "StorageError",
    "StoreWriter",
    "check_sample",
    "check_static",
    "format_store_info",
    "open_store",
    "plot_store_info",
    "store_info",
    "validate",
]
