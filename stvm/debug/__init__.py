"""Offline debugging of ST: breakpoints on ST statements, stepping, watch, set and force.

Layers, each usable on its own:

* `build`:   the debug build of a project (every variable on its instance, never in a Python
             local) and the map from generated lines to the ST statements they start.
* `scope`:   ST expressions typed and lowered in the scope of one POU instance (`print`, `set`,
             breakpoint conditions, `force`), with the project's own checker and code generator.
* `engine`:  the VM in a worker thread under `sys.settrace`, stopping at ST statements.
* `session`: what both front ends share: scenario, `--set`, the robot (lockstep, TCP, address).
* `console`: the `stvm debug` command line; `dap`: the Debug Adapter Protocol server (`stvm dap`).

Nothing here is imported by `stvm run`: the normal build keeps its local-variable cache and runs
without a trace function, so the debugger costs nothing when it is not used (see
bench/bench_debug_overhead.py). `cli` is the one module `stvm.cli` imports, and it imports the rest
only when a debug command runs.
"""
