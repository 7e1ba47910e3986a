"""Progress of long commands: a tqdm bar on a terminal, and in a log (no terminal) one plain line of
tqdm's figures (done/total, rate, time left) every ``every`` seconds and at the end."""

from __future__ import annotations

import sys
import time
from typing import Callable


def reporter(desc: str, unit: str, *, every: float = 30.0,
             follow_furthest: bool = False) -> Callable[..., None]:
    """A ``progress(done, total, desc=None)`` callback; call its ``close()`` when the work is over.

    A ``done`` below the last one, or a new ``total``, starts over (a new batch): a new bar, and in a
    log the rate counted from then; ``desc`` renames what follows. With ``follow_furthest`` (workers
    side by side report into one bar) a lower ``done`` is ignored on a terminal instead."""
    from tqdm import tqdm

    tty = sys.stdout.isatty()
    state = {"t0": time.perf_counter(), "last": 0.0, "seen": 0, "total": None, "bar": None, "desc": desc}

    def progress(done: int, total: int, desc: str | None = None) -> None:
        if desc is not None:
            state["desc"] = desc
        if tty:
            bar = state["bar"]
            if bar is None or bar.total != total or (done < bar.n and not follow_furthest):
                if bar is not None:
                    bar.close()
                bar = state["bar"] = tqdm(total=total, desc=state["desc"], unit=unit, file=sys.stdout,
                                          mininterval=1.0, dynamic_ncols=True)
            if done > bar.n:
                bar.update(done - bar.n)
            return
        now = time.perf_counter()
        if done < state["seen"] or total != state["total"]:
            state["t0"] = state["last"] = now
        if done >= total or now - state["last"] >= every:
            print(tqdm.format_meter(done, total, now - state["t0"], prefix=state["desc"], unit=unit), flush=True)
            state["last"] = now
        state["seen"], state["total"] = done, total

    def close() -> None:
        if state["bar"] is not None:
            state["bar"].close()

    progress.close = close  # type: ignore[attr-defined]
    return progress
