"""The store tests' packed store: 12 synthetic samples (``tests/store/stage_loop.py``), built once per session."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.store import stage_loop as sl

N = 12
"""Samples of the shared store (sample 5 failed)."""


def build(path: Path, n: int = N, **kw):
    """Stage every sample of a fresh store at ``path`` and pack it; returns the writer."""
    writer = sl.open_writer(path, n, durable=False)
    sl.stage_all(writer)
    assert writer.pack(**kw)
    return writer


@pytest.fixture(scope="session")
def packed(tmp_path_factory) -> Path:
    """A packed store that no test changes (copy it to damage it)."""
    path = tmp_path_factory.mktemp("store") / "ds"
    build(path)
    return path
