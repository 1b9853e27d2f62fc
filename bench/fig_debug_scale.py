"""Issue 33 items 1 and 4, from their standalone scripts (each also runs alone):

* debugging at speed (`bench/bench_debug_speed.py`): a scan under the debug engine with
  breakpoints set but not hit, against the same scan under `stvm run` (target <= 2x);
* the scale of a cell (`bench/bench_scale.py`): µs per scan for 1..16 robots in lockstep, the
  linear fit per robot and per FB instance (target <= 100 µs at 16 robots).

The scripts build their rows with the registry's `Row` and `for_loop_us`; this module only
registers them.
"""

from __future__ import annotations

from bench import bench_debug_speed, bench_scale
from bench.registry import Row, figure


@figure("debugging at speed", item="issue 33 item 1", tags=("debug",))
def debug_speed_figure(smoke: bool) -> list[Row]:
    return bench_debug_speed.run(smoke)


@figure("scale of a cell", item="issue 33 item 4", tags=("scale",))
def scale_figure(smoke: bool) -> list[Row]:
    return bench_scale.run(smoke)
