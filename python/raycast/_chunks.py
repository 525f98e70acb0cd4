"""Long calls in short pieces: each query runs over its rays, points or image rows in chunks
of about :data:`TARGET` seconds, one compiled call each. Python runs its signal handlers
between two calls, so Ctrl-C raises ``KeyboardInterrupt`` within about 0.1 s however long the
whole call is, and a ``progress`` hook hears how far it got. Every ray or point is answered on
its own, so the chunks change nothing in the results."""

from __future__ import annotations

import time
from typing import Callable

import numpy as np

#: Seconds one chunk should take.
TARGET = 0.03
#: Items in the first chunk, and the bounds of every chunk's size.
FIRST, SMALLEST, LARGEST = 4096, 256, 1 << 22


def _report(progress, done: int, total: int) -> None:
    """Tells ``progress`` that ``done`` of ``total`` items are done: a callable is called as
    ``progress(done, total)``; an object with ``update`` (a tqdm bar) gets the items since the
    last report."""
    if progress is None:
        return
    if hasattr(progress, "update"):
        last = getattr(progress, "_raycast_done", 0)
        progress.update(done - last)
        progress._raycast_done = done
    else:
        progress(done, total)


def pieces(total: int, call: Callable[[int, int], object], progress=None, unit: int = 1):
    """Yields ``(start, stop, call(start, stop))`` over ``0..total`` (once, empty, for no
    items), sized by time; an item weighs ``unit`` rays (an image row: its pixels)."""
    start, size = 0, max(1, FIRST // unit)
    while start < total or (total == 0 and start == 0):
        stop = min(total, start + size)
        began = time.perf_counter()
        result = call(start, stop)
        took = time.perf_counter() - began
        yield start, stop, result
        _report(progress, stop, total)
        if stop >= total:
            return
        start = stop
        scale = TARGET / took if took > 0 else 4.0
        items = int(size * unit * min(4.0, max(0.25, scale)))
        size = max(1, min(LARGEST, max(SMALLEST, items)) // unit)


def gather(total: int, call: Callable[[int, int], dict], progress=None, unit: int = 1) -> dict:
    """The dict of arrays ``call(0, total)`` would give (each with one row per item), made
    from chunks: each chunk's rows are copied into arrays allocated once, at the first chunk's
    dtypes and shapes."""
    out: dict = {}
    for start, stop, part in pieces(total, call, progress, unit):
        for key, value in part.items():
            if key not in out:
                out[key] = np.empty((total,) + value.shape[1:], value.dtype)
            out[key][start:stop] = value
    return out
