"""The cyclic garbage collector paused while stvm builds many small objects at once.

Parsing, checking and lowering build millions of objects (nodes, spans, facts) of which none is
garbage yet; the collector's passes over the growing heap took more than half of a
100,000-line load (bench/bench_large.py) and a fifth of the parser driver's build. One pause
for the whole front end: a nested pause leaves the collector to its owner.
"""

from __future__ import annotations

import contextlib
import gc


@contextlib.contextmanager
def collector_paused(age_survivors: bool = False):
    """The collector off for the block (left off when it was off already). With `age_survivors`
    the outermost pause ends by moving what the block built into the oldest generation (see
    `age_survivors`): for a load, whose objects live as long as the project."""
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            if age_survivors:
                _age_survivors()
            gc.enable()


def _age_survivors() -> None:
    """Move every object the paused section built straight into the oldest generation, unscanned.
    Left young, the first collections after a load would scan them all once a generation (a full
    pass over a 300 MB heap each: a third of instance building on a 100,000-line program); in
    the oldest generation only the usual full collections look at them (so cyclic garbage is
    still freed). Not while someone else holds the heap frozen (a real-time scan loop): unfreezing
    would hand its objects back to the collector."""
    if gc.get_freeze_count() == 0:
        gc.freeze()     # every generation into the permanent one, young count reset
        gc.unfreeze()   # the permanent generation back as the oldest
