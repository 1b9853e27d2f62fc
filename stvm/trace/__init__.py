"""Golden-trace testing: record watched variables once per scan in lockstep runs, write them
(.jsonl .csv .vcd WaveDrom .json), compare with a stored trace and report the first divergence.

    from stvm.trace import TraceSpec, run_trace, write_trace, read_trace, compare, render_report

    run = run_trace(TraceSpec(["st_src/PnP_Example.st"], scenario="st_src/scenarios/pnp_demo.toml",
                              watch=["PnP_Example_Instance.Prg_Step", "Cobot.*"], cycles=9000))
    write_trace(run.trace, "pnp.vcd")
    divergence = compare(read_trace("tests/golden/pnp.jsonl"), run.trace)   # None when equal

See docs/trace.md for the formats and the pytest plugin (`stvm.pytest_plugin`).
"""

from stvm.trace.golden import Divergence, Writer, compare, locate_writer, render_report
from stvm.trace.model import EventEntry, FrameEntry, SignalInfo, Trace
from stvm.trace.recorder import Recorder
from stvm.trace.run import TraceRun, TraceSpec, run_trace
from stvm.trace.signals import Signal, WatchError, select_signals
from stvm.trace.writers import TraceFormatError, read_trace, write_trace

__all__ = [
    "Divergence", "EventEntry", "FrameEntry", "Recorder", "Signal", "SignalInfo", "Trace", "TraceFormatError",
    "TraceRun", "TraceSpec", "WatchError", "Writer", "compare", "locate_writer", "read_trace", "render_report",
    "run_trace", "select_signals", "write_trace",
]
