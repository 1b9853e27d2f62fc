"""Front ends beside the scan loop (web HMI, OPC UA server): one way into the VM's variables.

    bridge = VariableBridge(vm)              # attaches to the VM's scan hooks
    watch = bridge.watch(["Cobot.Connected", "Main.x"], every_ns=50_000_000)
    snap = watch.latest()                    # Snapshot taken between two scans
    future = bridge.submit({"Main.x": 5})    # applied at the start of the next scan, all or nothing
    bridge.sample(["Main.y"])                # one snapshot at the next point between scans
    control = RunControl(vm)                 # pause / resume / step(n) from another thread

`catalog(vm)` lists every variable a front end may publish, as a tree of `VariableInfo` (the one
variable catalog of `stvm.runtime.catalog`, which the trace and the debugger list too).
"""

from stvm.frontend.bridge import Snapshot, VariableBridge, Watch, WriteRejected
from stvm.runtime.catalog import VariableInfo, catalog
from stvm.frontend.control import RunControl

__all__ = ["Snapshot", "VariableBridge", "Watch", "WriteRejected", "VariableInfo", "catalog", "RunControl"]
