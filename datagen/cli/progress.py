"""Progress of long commands: a tqdm bar on a terminal, and in a log (no terminal) one plain line of
tqdm's figures (done/total, rate, time left) every ``every`` seconds and at the end."""

from __future__ import annotations

import sys
import time
from typing import Callable


def reporter(desc: str, unit: str, *, every: float = 30.0) -> Callable[[int, int], None]:
    """A ``progress(done, total)`` callback; call its ``close()`` when the work is over."""
    from tqdm import tqdm

    tty = sys.stdout.isatty()
    state = {"t0": time.perf_counter(), "last": 0.0, "bar": None}

    def progress(done: int, total: int) -> None:
        if tty:
            bar = state["bar"]
            if bar is None:
                bar = state["bar"] = tqdm(total=total, desc=desc, unit=unit, file=sys.stdout, mininterval=1.0,
                                          dynamic_ncols=True)
            bar.update(done - bar.n)
            return
        now = time.perf_counter()
        if done >= total or now - state["last"] >= every:
            print(tqdm.format_meter(done, total, now - state["t0"], prefix=desc, unit=unit), flush=True)
            state["last"] = now

    def close() -> None:
        if state["bar"] is not None:
            state["bar"].close()

    progress.close = close  # type: ignore[attr-defined]
    return progress
