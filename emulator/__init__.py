"""A TM (Techman/Omron) robot speaking the Listen Node protocol, for tests without a robot.

Public API::

    import emulator
    server = emulator.start_server(host="127.0.0.1", port=0)   # background thread
    print(server.port)
    server.stop()

    link = emulator.InProcessLink(latency_ns=1_000_000)        # deterministic, virtual clock
    client = link.endpoint(); client.connect(); link.step(2_000_000)

See ``docs/emulator.md`` and the docstrings of :mod:`emulator.transport` and
:mod:`emulator.settings`.
"""

__all__ = [
    "ClientEndpoint", "Cperr", "DEFAULT_SETTINGS", "EmulatorSettings", "FaultPlan", "Frame", "FrameError",
    "InProcessLink", "ListenNodeFramer", "NO_FAULTS", "NodeState", "Robot", "TcpServer", "encode",
    "parse_fault", "parse_faults", "start_server",
]


# lazy: start-up (the robot's motion planner needs numpy; `stvm run` of a project without a
# robot, and the scenario reader, must not pay for it)
_HOMES = {
    "NO_FAULTS": "faults", "FaultPlan": "faults", "parse_fault": "faults", "parse_faults": "faults",
    "Cperr": "framing", "Frame": "framing", "FrameError": "framing", "ListenNodeFramer": "framing",
    "encode": "framing", "NodeState": "robot", "Robot": "robot", "DEFAULT_SETTINGS": "settings",
    "EmulatorSettings": "settings", "ClientEndpoint": "transport", "InProcessLink": "transport",
    "TcpServer": "transport", "start_server": "transport",
}


def __getattr__(name):
    home = _HOMES.get(name)
    if home is None:
        raise AttributeError(name)
    import importlib
    return getattr(importlib.import_module(f"emulator.{home}"), name)
