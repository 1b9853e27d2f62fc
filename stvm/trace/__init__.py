"""Golden-trace testing: record watched variables once per scan in lockstep runs, write them
(.jsonl .csv .vcd WaveDrom .json), compare with a stored trace and report the first divergence.

    from stvm.trace import TraceSpec, run_trace, write_trace, read_trace, compare, render_report

    run = run_trace(TraceSpec(["st_src/PnP_Example.st"], scenario="st_src/scenarios/pnp_demo.toml",
                              watch=["PnP_Example_Instance.Prg_Step", "Cobot.*"], cycles=9000))
    write_trace(run.trace, "pnp.vcd")
    divergence = compare(read_trace("tests/golden/pnp.jsonl"), run.trace)   # None when equal

See docs/trace.md for the formats and the pytest plugin (`stvm.pytest_plugin`).
"""

__all__ = [
    "Divergence", "EventEntry", "FrameEntry", "Recorder", "Signal", "SignalInfo", "Trace", "TraceFormatError",
    "TraceRun", "TraceSpec", "WatchError", "Writer", "compare", "locate_writer", "read_trace", "render_report",
    "run_trace", "select_signals", "write_trace",
]


# lazy: start-up (`stvm.trace.cli` registers `stvm trace` on every `stvm` call; the recorder and
# the writers load when a trace is made)
_HOMES = {
    "Divergence": "golden", "Writer": "golden", "compare": "golden", "locate_writer": "golden",
    "render_report": "golden",
    "EventEntry": "model", "FrameEntry": "model", "SignalInfo": "model", "Trace": "model",
    "Recorder": "recorder",
    "TraceRun": "run", "TraceSpec": "run", "run_trace": "run",
    "Signal": "signals", "WatchError": "signals", "select_signals": "signals",
    "TraceFormatError": "writers", "read_trace": "writers", "write_trace": "writers",
}


def __getattr__(name):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(name)
    import importlib
    return getattr(importlib.import_module(f"stvm.trace.{home}"), name)
