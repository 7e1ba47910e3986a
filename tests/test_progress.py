"""The progress reporter of long commands (``drape generate``, ``drape evaluate``) in a log."""

from __future__ import annotations

from datagen.cli.progress import reporter


def test_a_log_gets_a_line_at_the_end_and_a_new_batch_starts_over(capsys, monkeypatch):
    """Without a terminal: no line while a run is young, one line at its end, and a lower count (a
    new batch) is a new run whose line carries its new name and counts its own time."""
    clock = iter([0.0, 1.0, 2.0, 100.0, 101.0, 102.0])
    monkeypatch.setattr("datagen.cli.progress.time.perf_counter", lambda: next(clock))
    progress = reporter("batch of 4 scenes", "frame", every=30.0)
    progress(1, 10)
    progress(10, 10)
    assert capsys.readouterr().out.count("\n") == 1
    progress(2, 10, desc="batch of 2 scenes")  # t = 100: a new batch
    progress(5, 10)  # t = 101: too soon for a line
    progress(10, 10)  # t = 102: its end, 2 s after its start
    lines = capsys.readouterr().out.splitlines()
    assert len(lines) == 1 and lines[0].startswith("batch of 2 scenes")
    assert "00:02" in lines[0]
    progress.close()
