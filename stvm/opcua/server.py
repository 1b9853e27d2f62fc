"""The OPC UA server: asyncua in its own thread beside the scan loop, on the front-end bridge.

What the VM thread does for it, and nothing more (design: "the VM owns time"):

* **Monitored items** become bridge watches, grouped by sampling interval: a watch samples at
  the end of a scan, at most once per scan and no faster than the interval the client asked for
  (0 or -1: every scan). Its callback only drops the snapshot into a slot and, if none is
  pending, wakes the server loop (through a `LoopWaker`: a lock released, so the scan keeps the
  GIL; the relay thread makes the `call_soon_threadsafe` call between scans).
* **Reads** of variable values ask the bridge for a one-shot snapshot of exactly the nodes read,
  answered at the end of the running scan (or at once while a `RunControl` holds the VM), so a
  Read is a consistent snapshot between two scans. Only if no scan ends within `READ_WAIT_S`
  (the debugger stopped inside a scan) does the Read return the last values the server has.
* **Writes** are checked in the server thread against the ST type (BadTypeMismatch,
  BadOutOfRange) and the publish rules (BadNotWritable), then submitted as one bridge batch per
  Write request: applied together at the start of the next scan, or not at all.

The server loop forwards the newest snapshot of every watch at most every `FORWARD_S` of wall
time and puts only changed values into the nodes, so a fast virtual-clock run does not flood it:
between two forwards a client sees the newest sample, not every scan's.

Time stamps (Source and Server) are the VM clock of the sampled scan's start: on the virtual clock
`start DT + VM time` (1970-01-01T00:00:00Z + VM time by default: a client sees virtual time,
starting in 1970, advancing by the scan period per scan however fast the run goes); on the
real-time clock the host's UTC time of the scan's start.
"""

from __future__ import annotations

import asyncio
import contextvars
import copy
import dataclasses
import gc
import hashlib
import hmac
import logging
import re
import socket
import threading
import time
from typing import Any

from asyncua import Server, ua
from asyncua.crypto import uacrypto
from asyncua.crypto.permission_rules import User, UserRole
from asyncua.common.utils import ServiceError
from asyncua.server.internal_session import InternalSession

from stvm.frontend import RunControl, Snapshot, VariableBridge, WriteRejected, catalog
from stvm.frontend.alarms import AlarmList
from stvm.frontend.limits import LimitTable
from stvm.frontend.waker import LoopWaker
from stvm.opcua import bounds
from stvm.opcua.alarms import AlarmConditions
from stvm.opcua.arrays import PublishedArray, RangeError, find_arrays, flat, read_range, write_positions
from stvm.opcua.aspace_cache import init_server
from stvm.opcua.browse import ContinuationPoints
from stvm.opcua.config import OpcUaConfig, revise_interval as bounds_interval
from stvm.opcua.datatypes import BadWrite, datetime_of
from stvm.opcua.structs import PublishedStruct, StructTypes, find_structs, published_struct
from stvm.opcua.engineering import eu_information, eu_range
from stvm.opcua.nodes import GLOBALS_ID, RUNTIME_ID, NodeBuilder, PublishedVariable, describe, select, \
    walk_published
from stvm.semantics import types as t

FORWARD_S = 0.02          # newest snapshots go into the nodes at most this often (wall time)
FORWARD_NS = int(FORWARD_S * 1e9)
READ_WAIT_S = 1.0         # a Read waits this long for a scan to end before answering from the cache
WRITE_WAIT_S = 1.0        # a Write waits this long to see its batch applied (then answers Good: queued)
MAX_READS_WAITING = 32    # more concurrent Reads answer from the cache at once
MAX_SCAN_STEP = 10_000_000
HEARTBEAT_NS = 1_000_000_000   # Runtime.ScanCount / Time refresh without a subscription, in VM time

_REQUESTED_INTERVALS: contextvars.ContextVar[dict | None] = contextvars.ContextVar("stvm_sampling", default=None)
# the identity token being activated: asyncua hands its user manager the secure channel's client
# certificate for every token kind, so the manager must know whether that is the identity
_TOKEN_KIND: contextvars.ContextVar[str] = contextvars.ContextVar("stvm_token", default="anonymous")
_log = logging.getLogger("stvm.opcua")


class OpcUaServer:
    """Serve `vm`'s variables over OPC UA. Create it before the run starts, in the VM's thread;
    `start()` returns once the endpoint listens, `stop()` when the run has ended."""

    def __init__(self, vm, config: OpcUaConfig, bridge: VariableBridge | None = None,
                 run_control: bool = True, limit_table: LimitTable | None = None) -> None:
        self.vm = vm
        self.config = config
        self.roots = catalog(vm)
        self.selection = select(self.roots, config)   # first: a bad rule leaves the VM untouched
        self.variables: dict[str, PublishedVariable] = self.selection.variables
        # the operator limits every front end shares (BadOutOfRange, EURange, outputs read-only);
        # a mistake in the table is a LimitsError (a ValueError: `stvm run` exits 2)
        self.limit_table = limit_table if limit_table is not None else LimitTable.for_project(
            _ProjectFiles(config.manifest, config.root), vm)
        for var in self.variables.values():
            if var.writable and not self.limit_table.limits_for(var.path).writable:
                var.writable = False   # an output or status: read-only unless the table opens it
        self.bridge = bridge or VariableBridge(vm)
        self.control = RunControl(vm) if run_control and not vm.realtime else None
        self.base_ns = vm.base_ns
        self.realtime = vm.realtime
        self.start_dt_ns = vm.ctx.start_dt_ns
        self._initial = self._read_initial_values()
        self._by_nodeid: dict[ua.NodeId, PublishedVariable] = {}
        # array-valued variables beside the elements (stvm.opcua.arrays)
        self._arrays: dict[ua.NodeId, PublishedArray] = {}
        self._arrays_of_path: dict[str, list[PublishedArray]] = {}
        self._array_monitors: dict[int, tuple[PublishedArray, int]] = {}   # handle → (array, every_ns)
        self._group_arrays: dict[tuple, dict[PublishedArray, list[int]]] = {}
        self._loop: asyncio.AbstractEventLoop | None = None
        self._waker: LoopWaker | None = None   # wakes the loop for new snapshots (VM thread)
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._startup_error: BaseException | None = None
        self._server: Server | None = None
        self.url = config.endpoint.url
        self.ns = 0
        # real-time clock: the host's UTC time of VM time 0, taken when the first scan starts (a
        # start-up of seconds must not shift every time stamp); until then, the time of creation
        self._wall_offset_ns = time.time_ns()
        self._wall_offset_taken = False
        if self.realtime:
            vm.on_scan_start.append(self._take_wall_offset)
        # monitored items (server loop only)
        self._monitors: dict[int, tuple[str, int]] = {}     # callback handle → (path, every_ns)
        self._watches: dict[tuple, Any] = {}            # (every_ns, paths) → bridge watch
        self._group_handles: dict[tuple, dict[str, list[int]]] = {}   # watch key → path → handles
        self._group_sent: dict[tuple, dict[str, Any]] = {}  # watch key → path → value last notified
        self._heartbeat = None
        self._runtime_monitors: dict[int, int] = {}   # callback handle on a Runtime variable → every_ns
        self._runtime_watches: dict[int, Any] = {}    # every_ns → bridge watch (no paths: scan count, time)
        self._rebuild_pending = False
        # snapshot hand-over (VM thread writes slots, the loop pops them)
        self._inbox: dict[Any, Snapshot] = {}
        self._drain_pending = False
        self._last_drain = 0.0
        self._reads_waiting = 0
        self._runtime: dict[str, Any] = {}
        self._runtime_ids: set = set()
        self._stopping = False
        # the VM's one alarm list, shared with the HMI (an acknowledgement in either is seen in both)
        self.alarm_list = AlarmList.attach(self.bridge) if config.alarms else None
        self.conditions: AlarmConditions | None = None
        if config.start_paused and self.control is not None:
            self.control.pause()

    def _read_initial_values(self) -> dict[str, Any]:
        # the run has not started: the VM thread is this thread, idle
        return self.bridge.read_now(self.variables)

    # ================================================================ lifecycle (caller's thread)
    @property
    def writable_count(self) -> int:
        return sum(v.writable for v in self.variables.values())

    def start(self, timeout: float = 120.0) -> str:
        """Start the server thread; returns the endpoint URL (with the port chosen if it was 0).
        Raises RuntimeError (the cause chained) if the server cannot start."""
        _quiet_asyncua()
        self._thread = threading.Thread(target=self._thread_main, name="stvm-opcua", daemon=True)
        self._thread.start()
        if not self._ready.wait(timeout):
            raise RuntimeError("the OPC UA server did not start in time")
        error = self._startup_error
        if error is not None:
            if isinstance(error, OSError):   # one line: the port is taken, the address is not ours …
                reason = _os_reason(error)
                raise RuntimeError(f"cannot serve OPC UA on {self.config.endpoint.url}: {reason}") from None
            raise RuntimeError(f"the OPC UA server could not start on {self.config.endpoint.url}: "
                               f"{error}") from error
        return self.url

    def stop(self) -> None:
        """Stop serving (idempotent); the VM is released if it was held."""
        if self.control is not None:
            self.control.close()
        loop, self._loop = self._loop, None
        if loop is None or self._thread is None:
            return
        self._stopping = True
        try:
            loop.call_soon_threadsafe(loop.stop)
        except RuntimeError:
            pass
        self._thread.join(15)

    def __enter__(self) -> "OpcUaServer":
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.stop()

    # ================================================================ server thread
    def _thread_main(self) -> None:
        loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        try:
            loop.run_until_complete(self._setup())
        except BaseException as exc:   # noqa: BLE001 - reported by start()
            if self.alarm_list is not None:
                self.alarm_list.close()
            self._startup_error = exc
            self._ready.set()
            loop.close()
            return
        self._loop = loop
        self._waker = LoopWaker(loop, self._schedule_drain, name="stvm-opcua-wake")
        if self.conditions is not None:
            self.conditions.start(loop)
        self._ready.set()
        try:
            loop.run_forever()
        finally:
            waker, self._waker = self._waker, None
            waker.close()
            if self.conditions is not None:
                self.conditions.stop()
            for watch in list(self._watches.values()) + list(self._runtime_watches.values()) + \
                    ([self._heartbeat] if self._heartbeat else []):
                watch.close()
            self._watches = {}
            try:
                # asyncua's clock task sleeps 1 s between updates and stop() waits for it: cancel it
                time_task = self._server.iserver.time_task
                if time_task is not None:
                    time_task.cancel()
                    self._server.iserver.time_task = None
                loop.run_until_complete(self._server.stop())
                # sessions of clients still connected keep timeout and publish tasks: end them
                # here, not with "Task was destroyed but it is pending!" when the loop closes
                pending = [task for task in asyncio.all_tasks(loop) if not task.done()]
                for task in pending:
                    task.cancel()
                loop.run_until_complete(asyncio.gather(*pending, return_exceptions=True))
            except Exception:   # noqa: BLE001 - shutting down anyway
                pass
            loop.close()

    async def _setup(self) -> None:
        config = self.config
        endpoint = config.endpoint
        port = endpoint.port or _free_port(endpoint.host)
        host = f"[{endpoint.host}]" if ":" in endpoint.host else endpoint.host
        self.url = f"opc.tcp://{host}:{port}{endpoint.path or ''}"
        server = Server(user_manager=_UserManager(config))
        bounds.apply(server, config.limits)
        await init_server(server)   # the standard nodes from the signed cache (aspace_cache)
        server.set_endpoint(self.url + "/")
        server.set_server_name(f"stvm {config.project_name}")
        await server.set_application_uri(f"urn:stvm:{config.project_name}:server")
        if config.secure:
            await server.load_certificate(str(config.certificate))
            await server.load_private_key(str(config.private_key))
        policies, tokens = security_plan(config)
        server.set_security_policy(policies)
        server.set_identity_tokens(tokens)
        self.ns = await server.register_namespace(config.namespace_uri)
        self._server = server
        collecting = gc.isenabled()
        gc.disable()   # ~15 objects a node, none of them garbage: the collector would only re-scan them
        try:
            await self._build_address_space(server)
        finally:
            if collecting:
                gc.enable()
        if self.alarm_list is not None:
            self.conditions = AlarmConditions(self, self.alarm_list)
            await self.conditions.build(server)
        self._hook_sessions(server)
        self._hook_monitoring(server)
        await _start_listening(server, self.url)
        self._heartbeat = self.bridge.watch([], HEARTBEAT_NS, self._handover_for("heartbeat"))

    async def _build_address_space(self, server: Server) -> None:
        ns = self.ns
        aspace = server.iserver.aspace
        objects = server.nodes.objects
        builder = NodeBuilder(aspace, ns, self.base_ns / 1e6)
        enum_types = await self._enum_datatypes(server)
        globals_folder = await objects.add_folder(ua.NodeId(GLOBALS_ID, ns), ua.QualifiedName("Globals", ns))
        parents: dict[str, ua.NodeId] = {}
        for root in self.roots:
            if root.kind == "program":
                folder = await objects.add_folder(ua.NodeId(root.path, ns), ua.QualifiedName(root.name, ns))
                parents[root.path] = folder.nodeid
        stamp = self._timestamp(0)
        for node, parent in walk_published(self.roots, self.selection):
            parent_id = parents[parent.path] if parent is not None else globals_folder.nodeid
            var = self.variables.get(node.path)
            if var is None:
                parents[node.path] = builder.add_object(parent_id, node.path, node.name, describe(node)).nodeid
                continue
            datatype = var.uatype.datatype or enum_types[var.info.type.qualname or var.info.type.name]
            value = self._initial.get(node.path)
            var.last = value
            dv = ua.DataValue(ua.Variant(var.uatype.to_ua(value), var.uatype.variant),
                              SourceTimestamp=stamp, ServerTimestamp=stamp) if value is not None else \
                ua.DataValue(StatusCode=ua.StatusCode(ua.StatusCodes.BadWaitingForInitialData))
            limits = self.limit_table.limits_for(node.path)
            eu = eu_range(limits, node.type)
            data = builder.add_variable(parent_id, var, node.name, datatype, dv, analog=eu is not None)
            if eu is not None:
                builder.add_property(data, "EURange", ua.Variant(eu, ua.VariantType.ExtensionObject),
                                     ua.ObjectIds.Range)
            if limits.unit:
                builder.add_property(data, "EngineeringUnits",
                                     ua.Variant(eu_information(limits.unit), ua.VariantType.ExtensionObject),
                                     ua.ObjectIds.EUInformation)
            self._by_nodeid[var.nodeid] = var
        for node, array in find_arrays(self.roots, self.variables):
            if node.path not in parents:
                continue
            element = array.elements[0]
            datatype = element.uatype.datatype or enum_types[element.info.type.qualname or element.info.type.name]
            values = [e.last for e in array.elements]
            dv = ua.DataValue(array.variant(values), SourceTimestamp=stamp, ServerTimestamp=stamp) \
                if None not in values else ua.DataValue(StatusCode=ua.StatusCode(ua.StatusCodes.BadWaitingForInitialData))
            array.last = tuple(values)
            builder.add_value_variable(parents[node.path], array, datatype, dv, describe(node))
            self._add_composite(array)
        await self._add_structs(server, builder, parents, enum_types, stamp)
        await self._add_runtime(server, objects)

    def _add_composite(self, composite) -> None:
        """An array or struct variable: read, written and monitored through its element variables."""
        self._arrays[composite.nodeid] = composite
        for path in composite.paths:
            self._arrays_of_path.setdefault(path, []).append(composite)

    async def _add_structs(self, server: Server, builder: NodeBuilder, parents: dict, enum_types: dict, stamp) -> None:
        """The STRUCT DataTypes and a `<path>.@Value` ExtensionObject variable per struct instance."""
        types = StructTypes(self.ns, enum_types)
        found = [(node, ty) for node, ty in find_structs(self.roots, self.variables, types) if node.path in parents]
        if not found:
            return
        await types.build(server)
        for node, ty in found:
            struct = published_struct(node, ty, self.variables, types)
            values = [e.last for e in struct.elements]
            dv = ua.DataValue(struct.variant(values), SourceTimestamp=stamp, ServerTimestamp=stamp) \
                if None not in values else ua.DataValue(StatusCode=ua.StatusCode(ua.StatusCodes.BadWaitingForInitialData))
            struct.last = tuple(values)
            builder.add_value_variable(parents[node.path], struct, types.datatypes[struct.type_key], dv,
                                       describe(node))
            self._add_composite(struct)

    async def _enum_datatypes(self, server: Server) -> dict[str, ua.NodeId]:
        """One Enumeration DataType per ST enum type that a published variable has."""
        found: dict[str, t.EnumType] = {}
        for var in self.variables.values():
            ty = var.info.type
            if isinstance(ty, t.EnumType):
                found.setdefault(ty.qualname or ty.name, ty)
        ns = self.ns
        result = {}
        for key, ty in found.items():
            name = ty.name
            dtype = await server.nodes.enum_data_type.add_data_type(ua.NodeId(f"@Type.{key}", ns),
                                                                   ua.QualifiedName(name, ns))
            definition = ua.EnumDefinition(Fields=[ua.EnumField(Name=member, Value=value,
                                                                DisplayName=ua.LocalizedText(member))
                                                   for member, value in ty.members])
            await dtype.write_data_type_definition(definition)
            values = [value for _, value in ty.members]
            if values == list(range(len(values))):
                await dtype.add_property(ua.NodeId(f"@Type.{key}.EnumStrings", ns), ua.QualifiedName("EnumStrings", 0),
                                         [ua.LocalizedText(member) for member, _ in ty.members],
                                         ua.VariantType.LocalizedText, ua.NodeId(ua.ObjectIds.LocalizedText))
            else:
                await dtype.add_property(ua.NodeId(f"@Type.{key}.EnumValues", ns), ua.QualifiedName("EnumValues", 0),
                                         [ua.EnumValueType(Value=value, DisplayName=ua.LocalizedText(member))
                                          for member, value in ty.members],
                                         ua.VariantType.ExtensionObject, ua.NodeId(ua.ObjectIds.EnumValueType))
            result[key] = dtype.nodeid
        return result

    async def _add_runtime(self, server: Server, objects) -> None:
        ns = self.ns
        runtime = await objects.add_object(ua.NodeId(RUNTIME_ID, ns), ua.QualifiedName("Runtime", ns))
        initial = {"ScanCount": ua.Variant(0, ua.VariantType.UInt64),
                   "Time": ua.Variant(self._timestamp(0), ua.VariantType.DateTime),
                   "Paused": ua.Variant(bool(self.config.start_paused and self.control), ua.VariantType.Boolean),
                   "Clock": ua.Variant("real-time" if self.realtime else "virtual", ua.VariantType.String)}
        for name, variant in initial.items():
            node = await runtime.add_variable(ua.NodeId(f"{RUNTIME_ID}.{name}", ns), ua.QualifiedName(name, ns), variant)
            self._runtime[name] = node.nodeid
        self._runtime_ids = set(self._runtime.values())
        if self.control is None:
            return   # stepping only on the virtual clock, and not under the debugger
        count = ua.Argument(Name="Scans", DataType=ua.NodeId(ua.ObjectIds.UInt32), ValueRank=-1,
                            Description=ua.LocalizedText(f"number of scans to run (1..{MAX_SCAN_STEP})"))
        done = ua.Argument(Name="ScanCount", DataType=ua.NodeId(ua.ObjectIds.UInt64), ValueRank=-1,
                           Description=ua.LocalizedText("scans run since the start, once the steps are done"))
        await runtime.add_method(ua.NodeId(f"{RUNTIME_ID}.Scan", ns), ua.QualifiedName("Scan", ns),
                                 _arity(self._method_scan, 1), [count], [done])
        await runtime.add_method(ua.NodeId(f"{RUNTIME_ID}.Pause", ns), ua.QualifiedName("Pause", ns),
                                 _arity(self._method_pause, 0), [], [])
        await runtime.add_method(ua.NodeId(f"{RUNTIME_ID}.Resume", ns), ua.QualifiedName("Resume", ns),
                                 _arity(self._method_resume, 0), [], [])

    # ---------------------------------------------------------------- time
    def _take_wall_offset(self, vm) -> None:   # VM thread, at the start of every scan: one test
        if not self._wall_offset_taken:
            self._wall_offset_taken = True
            self._wall_offset_ns = time.time_ns() - vm.now_ns

    def _timestamp(self, now_ns: int):
        if self.realtime:
            return datetime_of(self._wall_offset_ns + now_ns)
        return datetime_of(self.start_dt_ns + now_ns)

    # ---------------------------------------------------------------- snapshots → nodes
    def _handover_for(self, key):
        def handover(snapshot: Snapshot) -> None:   # VM thread: hand over, never block
            self._inbox[key] = snapshot
            waker = self._waker
            if not self._drain_pending and not self._stopping and waker is not None:
                self._drain_pending = True
                waker.wake()   # a lock released: the GIL stays with the scan (stvm/frontend/waker.py)
        return handover

    def _schedule_drain(self) -> None:
        delay = self._last_drain + FORWARD_S - time.monotonic()
        if delay > 0:
            self._loop.call_later(delay, self._start_drain)
        else:
            self._start_drain()

    def _start_drain(self) -> None:
        asyncio.ensure_future(self._drain())

    async def _drain(self) -> None:
        self._drain_pending = False           # first: a snapshot arriving from now on wakes us again
        self._last_drain = time.monotonic()
        snapshots = []
        for key in list(self._inbox):
            snapshot = self._inbox.pop(key, None)
            if snapshot is not None:
                snapshots.append((snapshot, key))
        snapshots.sort(key=lambda pair: (pair[0].scan, pair[0].version))
        for snapshot, key in snapshots:
            await self._apply(snapshot, key)

    async def _apply(self, snapshot: Snapshot, key=None) -> None:
        """Put the snapshot's changed values into the nodes. The sample of a subscription watch
        (`key`) notifies only the monitored items of that sampling interval, each when its value
        differs from the one that group last sent: a node monitored every scan and every 100 ms
        notifies each at its own rate. One-shot samples (reads) notify nobody."""
        stamp = self._timestamp(snapshot.now_ns)
        handles = self._group_handles.get(key) if key is not None else None
        sent = self._group_sent.setdefault(key, {}) if handles is not None else None
        changed_arrays: set[PublishedArray] = set()
        for path, value in snapshot.values.items():
            var = self.variables.get(path)
            if var is None or value is None:
                continue
            dv = None
            if value != var.last:
                var.last = value
                if path in self._arrays_of_path:
                    changed_arrays.update(self._arrays_of_path[path])
                dv = var.value_attr.value = ua.DataValue(
                    ua.Variant(var.uatype.to_ua(value), var.uatype.variant), SourceTimestamp=stamp,
                    ServerTimestamp=stamp)
            if handles is None or sent.get(path, _NOTHING) == value:
                continue
            sent[path] = value
            dv = dv or ua.DataValue(ua.Variant(var.uatype.to_ua(value), var.uatype.variant),
                                    SourceTimestamp=stamp, ServerTimestamp=stamp)
            callbacks = var.value_attr.datachange_callbacks
            for handle in handles.get(path, ()):
                callback = callbacks.get(handle)
                if callback is not None:
                    await _notify(callback, handle, dv)
        await self._apply_arrays(changed_arrays, key, sent, stamp)
        await self._set_runtime("ScanCount", ua.Variant(snapshot.scan + 1, ua.VariantType.UInt64), stamp)
        await self._set_runtime("Time", ua.Variant(stamp, ua.VariantType.DateTime), stamp)
        if self.control is not None:
            await self._set_runtime("Paused", ua.Variant(self.control.paused, ua.VariantType.Boolean), stamp)

    async def _apply_arrays(self, changed: set[PublishedArray], key, sent: dict | None, stamp) -> None:
        """The array variables whose elements changed take the new values; the array items of
        this sampling group (`key`) are notified when their array differs from what they last got."""
        for array in changed:
            values = tuple(e.last for e in array.elements)
            if None in values or values == array.last:
                continue
            array.last = values
            array.value_attr.value = ua.DataValue(array.variant(values), SourceTimestamp=stamp, ServerTimestamp=stamp)
        groups = self._group_arrays.get(key) if key is not None else None
        if not groups:
            return
        for array, handles in groups.items():
            if array.last is None or sent.get(array, _NOTHING) == array.last:
                continue
            sent[array] = array.last
            dv = array.value_attr.value
            callbacks = array.value_attr.datachange_callbacks
            for handle in handles:
                callback = callbacks.get(handle)
                if callback is not None:
                    await _notify(callback, handle, dv)

    async def _set_runtime(self, name: str, variant: ua.Variant, stamp) -> None:
        attr = self._server.iserver.aspace[self._runtime[name]].attributes[ua.AttributeIds.Value]
        old = attr.value
        if old is not None and old.Value == variant:
            return
        await self._set_value(attr, ua.DataValue(variant, SourceTimestamp=stamp, ServerTimestamp=stamp))

    @staticmethod
    async def _set_value(attr, dv: ua.DataValue) -> None:
        attr.value = dv
        for handle, callback in list(attr.datachange_callbacks.items()):
            await _notify(callback, handle, dv)

    async def _fresh(self, paths: list[str], key=None) -> Snapshot | None:
        """A one-shot snapshot of `paths` put into the nodes (notifying the monitored items of
        watch group `key`, if given); None if no scan ended in time."""
        if self._reads_waiting >= MAX_READS_WAITING:
            return None
        try:
            future = self.bridge.sample(paths)
        except WriteRejected:
            return None
        self._reads_waiting += 1
        try:
            snapshot = await asyncio.wait_for(asyncio.wrap_future(future), READ_WAIT_S)
        except asyncio.TimeoutError:
            return None
        finally:
            self._reads_waiting -= 1
        await self._apply(snapshot, key)
        return snapshot

    # ---------------------------------------------------------------- services
    def _hook_sessions(self, server: Server) -> None:
        iserver = server.iserver
        owner = self

        limits = self.config.limits
        sessions: set = set()

        def items_of(session) -> int:
            return sum(len(sub.monitored_item_srv._monitored_items)
                       for sub in iserver.subscription_service.subscriptions.values()
                       if sub.session_id == session.session_id)

        def subscriptions_of(session) -> int:
            return sum(sub.session_id == session.session_id
                       for sub in iserver.subscription_service.subscriptions.values())

        class Session(InternalSession):
            async def create_session(self, params, sockname=None):
                if len(sessions) >= limits.max_sessions:
                    bounds.log_limited(f"OPC UA session refused: {limits.max_sessions} sessions open (max_sessions)")
                    raise ServiceError(ua.StatusCodes.BadTooManySessions)
                result = await super().create_session(params, sockname=sockname)
                sessions.add(self)
                return result

            async def close_session(self, delete_subs: bool = True) -> None:
                sessions.discard(self)
                await super().close_session(delete_subs)

            async def create_subscription(self, params, callback, request_callback=None):
                if subscriptions_of(self) >= limits.max_subscriptions_per_session:
                    raise ServiceError(ua.StatusCodes.BadTooManySubscriptions)
                # OPC UA Part 4 §5.13.2: the server revises the interval to one it supports (NaN: the fastest)
                interval = bounds_interval(params.RequestedPublishingInterval, limits.min_publishing_interval,
                                           limits.max_interval)
                params.RequestedPublishingInterval = limits.min_publishing_interval if interval is None else interval
                return await super().create_subscription(params, callback, request_callback=request_callback)

            def modify_subscription(self, params):
                # asyncua keeps the interval it revised at creation; the request's values need no check
                return super().modify_subscription(params)

            async def create_monitored_items(self, params: ua.CreateMonitoredItemsParameters):
                room = limits.max_monitored_items_per_session - items_of(self)
                return await owner._create_monitored_items(self, params, room)

            def modify_monitored_items(self, params: ua.ModifyMonitoredItemsParameters):
                return owner._modify_monitored_items(self, params)

            def activate_session(self, params: ua.ActivateSessionParameters, peer_certificate):
                token = params.UserIdentityToken
                kind = "username" if isinstance(token, ua.UserNameIdentityToken) else \
                    "certificate" if isinstance(token, ua.X509IdentityToken) else "anonymous"
                reset = _TOKEN_KIND.set(kind)
                try:
                    return super().activate_session(params, peer_certificate)
                finally:
                    _TOKEN_KIND.reset(reset)

            async def browse(self, params: ua.BrowseParameters) -> list[ua.BrowseResult]:
                # at most RequestedMaxReferencesPerNode per node, the rest by BrowseNext (stvm.opcua.browse)
                points = self.__dict__.setdefault("_continuation_points", ContinuationPoints())
                return [points.page(result, params.RequestedMaxReferencesPerNode)
                        for result in iserver.view_service.browse(params)]

            def browse_next_pages(self, params: ua.BrowseNextParameters) -> list[ua.BrowseResult]:
                points = self.__dict__.setdefault("_continuation_points", ContinuationPoints())
                return points.next(params)

            async def history_read(self, params: ua.HistoryReadParameters) -> list[ua.HistoryReadResult]:
                # no history is kept (of values or events): say so per node, as Part 4 §5.11.3.4's
                # operation-level Bad_HistoryOperationUnsupported ("not supported for the requested
                # node"); a node that does not exist is Bad_NodeIdUnknown (asyncua would answer
                # Good with no data)
                return [ua.HistoryReadResult(StatusCode=ua.StatusCode(
                    ua.StatusCodes.BadHistoryOperationUnsupported if item.NodeId in iserver.aspace
                    else ua.StatusCodes.BadNodeIdUnknown)) for item in params.NodesToRead]

            async def read(self, params: ua.ReadParameters) -> list[ua.DataValue]:
                return await owner._read(self, params)

            async def write(self, params: ua.WriteParameters) -> list[ua.StatusCode]:
                return await owner._write(self, params)

        def create_session(name: str, user: User = User(role=UserRole.Anonymous), external: bool = False):
            return Session(iserver, iserver.aspace, iserver.subscription_service, name, user=user, external=external)
        iserver.create_session = create_session

    async def _read(self, session: InternalSession, params: ua.ReadParameters) -> list[ua.DataValue]:
        ours = [(i, var) for i, item in enumerate(params.NodesToRead)
                if item.AttributeId == ua.AttributeIds.Value and (var := self._by_nodeid.get(item.NodeId))]
        arrays = [(i, array) for i, item in enumerate(params.NodesToRead)
                  if item.AttributeId == ua.AttributeIds.Value and (array := self._arrays.get(item.NodeId))]
        runtime = any(item.NodeId in self._runtime_ids for item in params.NodesToRead)
        paths = [var.path for _, var in ours] + [p for _, array in arrays for p in array.paths]
        snapshot = await self._fresh(list(dict.fromkeys(paths))) if ours or arrays or runtime else None
        results = await InternalSession.read(session, params)
        for i, array in arrays:
            index_range = params.NodesToRead[i].IndexRange
            if index_range and isinstance(array, PublishedStruct):   # a struct is a scalar
                results[i] = ua.DataValue(StatusCode=ua.StatusCode(_index_range_status(index_range)))
            elif index_range and array.last is not None and results[i].StatusCode.is_good():
                try:
                    results[i] = dataclasses.replace(results[i], Value=read_range(array, list(array.last), index_range))
                except RangeError as bad:
                    results[i] = ua.DataValue(StatusCode=ua.StatusCode(bad.status))
        for i, _ in ours:
            index_range = params.NodesToRead[i].IndexRange
            if index_range:   # every published variable is a scalar: no element of it to read
                results[i] = ua.DataValue(StatusCode=ua.StatusCode(_index_range_status(index_range)))
        if snapshot is not None:
            stamp = self._timestamp(snapshot.now_ns)
            for i, _ in ours + arrays:
                if results[i].StatusCode is None or results[i].StatusCode.is_good():
                    results[i] = dataclasses.replace(results[i], ServerTimestamp=stamp)
        return results

    async def _write(self, session: InternalSession, params: ua.WriteParameters) -> list[ua.StatusCode]:
        items = params.NodesToWrite
        results: list[ua.StatusCode | None] = [None] * len(items)
        batch: dict[str, Any] = {}
        index_of: dict[str, list[int]] = {}
        others: list[int] = []
        for i, item in enumerate(items):
            array = self._arrays.get(item.NodeId)
            if array is not None:
                status = self._array_write(session, array, item, batch)
                if status is None:
                    for path in array.paths:
                        if path in batch:
                            index_of.setdefault(path, []).append(i)
                else:
                    results[i] = ua.StatusCode(status)
                continue
            var = self._by_nodeid.get(item.NodeId)
            if var is None:
                if item.NodeId in self._runtime_ids and item.AttributeId == ua.AttributeIds.Value or \
                        item.NodeId.NamespaceIndex == self.ns and item.NodeId in self._server.iserver.aspace:
                    # the VM's own state, properties (EURange …), objects: nothing of ours is
                    # writable but the published variables' values
                    results[i] = ua.StatusCode(ua.StatusCodes.BadNotWritable)
                else:
                    others.append(i)
                continue
            status = self._check_write(session, var, item)
            if status is None:
                try:
                    value = var.uatype.from_ua(item.Value.Value if item.Value else None)
                    problem = self.limit_table.limits_for(var.path).check(value)
                    if problem is not None:   # the operator's range, NaN and ±inf (the HMI's table)
                        raise BadWrite(ua.StatusCodes.BadOutOfRange, problem)
                    batch[var.path] = value
                    index_of.setdefault(var.path, []).append(i)
                    continue
                except BadWrite as bad:
                    _log.info("write %s refused: %s", var.path, bad)
                    status = bad.status
                except (AttributeError, TypeError, ValueError):
                    status = ua.StatusCodes.BadTypeMismatch
            results[i] = ua.StatusCode(status)
        if others:
            sub = ua.WriteParameters(NodesToWrite=[items[i] for i in others])
            for i, status in zip(others, await InternalSession.write(session, sub)):
                results[i] = status
        if batch:
            for path, status in (await self._submit(batch)).items():
                for i in index_of[path]:
                    if results[i] is None or results[i].is_good():   # an array item: its first bad element
                        results[i] = ua.StatusCode(status)
        return results   # type: ignore[return-value]

    def _array_write(self, session: InternalSession, array: PublishedArray, item: ua.WriteValue,
                     batch: dict[str, Any]) -> int | None:
        """Put the elements a Write of an array variable sets into `batch`; a status if refused
        (nothing of it is put in then). Every element is checked as its own variable is: its
        type, its range, the limits table."""
        if item.AttributeId != ua.AttributeIds.Value:
            return ua.StatusCodes.BadNotWritable
        if not array.writable:
            return ua.StatusCodes.BadNotWritable
        user = session.user
        if user is None or user.role not in (UserRole.User, UserRole.Admin):
            return ua.StatusCodes.BadUserAccessDenied
        variant = item.Value.Value if item.Value is not None else None
        if variant is None or variant.Value is None:
            return ua.StatusCodes.BadTypeMismatch
        if isinstance(array, PublishedStruct):
            if item.IndexRange:      # a struct is a scalar (Part 4 §5.11.4.2)
                status = _index_range_status(item.IndexRange)
                return ua.StatusCodes.BadWriteNotSupported if status == ua.StatusCodes.BadIndexRangeNoData else status
            try:
                values = array.split(variant.Value)
            except (TypeError, ValueError):
                return ua.StatusCodes.BadTypeMismatch
            positions = list(range(len(values)))
            variants = [e.uatype.variant for e in array.elements]
        else:
            values = flat(variant.Value) if isinstance(variant.Value, list) else None
            if values is None:
                return ua.StatusCodes.BadTypeMismatch
            try:
                positions = write_positions(array, item.IndexRange, len(values))
            except RangeError as bad:
                return bad.status
            variants = [variant.VariantType] * len(array.elements)
        staged = {}
        for position, value in zip(positions, values):
            element = array.elements[position]
            try:
                converted = element.uatype.from_ua(ua.Variant(value, variants[position]))
                problem = self.limit_table.limits_for(element.path).check(converted)
                if problem is not None:
                    raise BadWrite(ua.StatusCodes.BadOutOfRange, f"{element.path}: {problem}")
            except BadWrite as bad:
                _log.info("write %s refused: %s", array.path, bad)
                return bad.status
            except (AttributeError, TypeError, ValueError):
                return ua.StatusCodes.BadTypeMismatch
            staged[element.path] = converted
        batch.update(staged)
        return None

    @staticmethod
    def _check_write(session: InternalSession, var: PublishedVariable, item: ua.WriteValue) -> int | None:
        if item.AttributeId != ua.AttributeIds.Value:
            return ua.StatusCodes.BadNotWritable
        if item.IndexRange:   # OPC UA Part 4 §5.11.4.2: an IndexRange that cannot be written
            status = _index_range_status(item.IndexRange)
            return ua.StatusCodes.BadWriteNotSupported if status == ua.StatusCodes.BadIndexRangeNoData else status
        if not var.writable:
            return ua.StatusCodes.BadNotWritable
        user = session.user
        if user is None or user.role not in (UserRole.User, UserRole.Admin):
            return ua.StatusCodes.BadUserAccessDenied
        if item.Value is None or item.Value.Value is None:
            return ua.StatusCodes.BadTypeMismatch
        return None

    async def _submit(self, batch: dict[str, Any]) -> dict[str, int]:
        """Submit one all-or-nothing batch; the status per path."""
        statuses = {path: ua.StatusCodes.Good for path in batch}
        while batch:
            try:
                future = self.bridge.submit(batch)
                break
            except WriteRejected as exc:
                if exc.path is None or exc.path not in batch:   # "busy": the whole request waits too long
                    return {path: ua.StatusCodes.BadResourceUnavailable for path in statuses}
                statuses[exc.path] = ua.StatusCodes.BadOutOfRange if "range" in exc.reason \
                    else ua.StatusCodes.BadTypeMismatch
                batch = {p: v for p, v in batch.items() if p != exc.path}
        else:
            return statuses
        try:
            await asyncio.wait_for(asyncio.shield(asyncio.wrap_future(future)), WRITE_WAIT_S)
        except asyncio.TimeoutError:
            return statuses   # queued: applied when the next scan starts (the debugger is stopped)
        except WriteRejected:
            return {path: ua.StatusCodes.BadInvalidState if status == ua.StatusCodes.Good else status
                    for path, status in statuses.items()}
        asyncio.ensure_future(self._fresh(list(batch)))   # monitored items see the new values
        return statuses

    # ---------------------------------------------------------------- monitored items
    async def _create_monitored_items(self, session: InternalSession, params: ua.CreateMonitoredItemsParameters,
                                      room: int) -> list[ua.MonitoredItemCreateResult]:
        """asyncua's CreateMonitoredItems for the items that fit the session's cap (`room`) and ask
        for a sampling interval; the others get their Bad status without reaching asyncua."""
        limits = self.config.limits
        results: list[ua.MonitoredItemCreateResult | None] = [None] * len(params.ItemsToCreate)
        accepted: list[int] = []
        requested: dict[ua.NodeId, float] = {}
        for i, item in enumerate(params.ItemsToCreate):
            interval = bounds_interval(item.RequestedParameters.SamplingInterval, 0.0, limits.max_interval)
            if interval is None:
                status = ua.StatusCodes.BadInvalidArgument        # NaN: no interval at all (stvm's choice)
            elif len(accepted) >= room:
                status = ua.StatusCodes.BadTooManyMonitoredItems
            else:
                accepted.append(i)
                requested[item.ItemToMonitor.NodeId] = interval
                continue
            results[i] = ua.MonitoredItemCreateResult(StatusCode=ua.StatusCode(status))
        if len(accepted) < len(results):
            bounds.log_limited(f"OPC UA CreateMonitoredItems: {len(results) - len(accepted)} of {len(results)} "
                               f"items refused (max_monitored_items_per_session {limits.max_monitored_items_per_session}"
                               f" or NaN sampling interval)")
        if accepted:
            sub = copy.copy(params)
            sub.ItemsToCreate = [params.ItemsToCreate[i] for i in accepted]
            token = _REQUESTED_INTERVALS.set(requested)
            try:
                created = await InternalSession.create_monitored_items(session, sub)
            finally:
                _REQUESTED_INTERVALS.reset(token)
            for i, result in zip(accepted, created):
                item = params.ItemsToCreate[i]
                if result.StatusCode.is_good() and item.ItemToMonitor.NodeId in self._by_nodeid:
                    result.RevisedSamplingInterval = self._every_ns(requested[item.ItemToMonitor.NodeId]) / 1e6 \
                        or max(self.base_ns, FORWARD_NS) / 1e6
                results[i] = result
        return results   # type: ignore[return-value]

    def _modify_monitored_items(self, session: InternalSession, params: ua.ModifyMonitoredItemsParameters):
        """asyncua's ModifyMonitoredItems; a NaN sampling interval is refused per item, ±inf revised."""
        limits = self.config.limits
        results: list[ua.MonitoredItemModifyResult | None] = [None] * len(params.ItemsToModify)
        accepted = []
        for i, item in enumerate(params.ItemsToModify):
            interval = bounds_interval(item.RequestedParameters.SamplingInterval, 0.0, limits.max_interval)
            if interval is None:
                results[i] = ua.MonitoredItemModifyResult(StatusCode=ua.StatusCode(ua.StatusCodes.BadInvalidArgument))
            else:
                item.RequestedParameters.SamplingInterval = interval
                accepted.append(i)
        if accepted:
            sub = copy.copy(params)
            sub.ItemsToModify = [params.ItemsToModify[i] for i in accepted]
            for i, result in zip(accepted, InternalSession.modify_monitored_items(session, sub)):
                results[i] = result
        return results

    def _every_ns(self, requested_ms: float) -> int:
        """Sampling interval in VM time: the client's if slower than a scan, else every scan (0)."""
        if requested_ms is None or requested_ms <= 0:
            return 0
        every = int(requested_ms * 1e6)
        return every if every > self.base_ns else 0

    def _hook_monitoring(self, server: Server) -> None:
        aspace = server.iserver.aspace
        add, delete = aspace.add_datachange_callback, aspace.delete_datachange_callback

        def add_datachange_callback(nodeid, attr, callback):
            status, handle = add(nodeid, attr, callback)
            var = self._by_nodeid.get(nodeid)
            if status.is_good() and attr == ua.AttributeIds.Value:
                requested = (_REQUESTED_INTERVALS.get() or {}).get(nodeid, 0.0)
                if var is not None:
                    self._monitors[handle] = (var.path, self._every_ns(requested))
                    self._rebuild_soon()
                elif nodeid in self._arrays:
                    self._array_monitors[handle] = (self._arrays[nodeid], self._every_ns(requested))
                    self._rebuild_soon()
                elif nodeid in self._runtime_ids:
                    # ScanCount and Time at the client's interval, not only at the 1 s heartbeat
                    self._runtime_monitors[handle] = self._every_ns(requested)
                    self._rebuild_soon()
            return status, handle

        def delete_datachange_callback(handle):
            delete(handle)
            if self._monitors.pop(handle, None) is not None or self._runtime_monitors.pop(handle, None) is not None \
                    or self._array_monitors.pop(handle, None) is not None:
                self._rebuild_soon()

        aspace.add_datachange_callback = add_datachange_callback
        aspace.delete_datachange_callback = delete_datachange_callback

    def _rebuild_soon(self) -> None:
        # many items come in one request (or leave with one session): one rebuild for all
        if not self._rebuild_pending:
            self._rebuild_pending = True
            asyncio.get_running_loop().call_later(0.005, self._rebuild_watches)

    def _rebuild_watches(self) -> None:
        """One watch per sampling interval in use, over the paths monitored at that interval."""
        self._rebuild_pending = False
        groups: dict[int, dict[str, list[int]]] = {}
        for handle, (path, every) in self._monitors.items():
            groups.setdefault(every, {}).setdefault(path, []).append(handle)
        array_groups: dict[int, dict[PublishedArray, list[int]]] = {}
        for handle, (array, every) in self._array_monitors.items():
            array_groups.setdefault(every, {}).setdefault(array, []).append(handle)
            by_path = groups.setdefault(every, {})
            for path in array.paths:
                by_path.setdefault(path, [])   # sampled for the array; no element item of its own
        watches, handles, arrays = {}, {}, {}
        for every, by_path in groups.items():
            key = (every, tuple(sorted(by_path)))
            arrays[key] = array_groups.get(every, {})
            watch = self._watches.pop(key, None)
            if watch is None:
                # items asking for every scan are read once per forwarding period (FORWARD_S) of VM
                # time: the server puts only the newest sample into the nodes every FORWARD_S of wall
                # time anyway, so reading them at every scan end cost the scan loop ~0.03 µs a value
                # for samples overwritten unseen (issue 33 item 3). VM time, not wall time: the
                # samples stay deterministic on the virtual clock, and the scans between two reads
                # pay one comparison. Runtime.Scan/Pause read every such group once more at their end.
                watch = self.bridge.watch(list(key[1]), every or FORWARD_NS, self._handover_for(key),
                                          changes_only=True)
            watches[key] = watch
            handles[key] = by_path
        for old in self._watches.values():
            old.close()
        intervals = set(self._runtime_monitors.values())
        for every in list(self._runtime_watches):
            if every not in intervals:
                self._runtime_watches.pop(every).close()
        for every in intervals - set(self._runtime_watches):
            self._runtime_watches[every] = self.bridge.watch([], every, self._handover_for(("runtime", every)))
        self._group_sent = {key: sent for key, sent in self._group_sent.items() if key in watches}
        self._watches, self._group_handles, self._group_arrays = watches, handles, arrays

    @property
    def monitored_paths(self) -> set[str]:
        """Paths sampled for subscriptions right now (for tests and the bench)."""
        return {path for key in self._watches for path in key[1]}

    # ---------------------------------------------------------------- Runtime methods
    async def _method_scan(self, parent, count=None):
        scans = count.Value if isinstance(count, ua.Variant) else count
        if not isinstance(scans, int) or isinstance(scans, bool):
            return ua.StatusCode(ua.StatusCodes.BadTypeMismatch)
        if not 1 <= scans <= MAX_SCAN_STEP:
            return ua.StatusCode(ua.StatusCodes.BadOutOfRange)
        if self._rebuild_pending:
            # items monitored before this call are sampled in its scans, however soon it follows
            # (their watches would otherwise wait for the deferred rebuild)
            self._rebuild_watches()
        try:
            done = await asyncio.wrap_future(self.control.step(scans))
        except RuntimeError:
            return ua.StatusCode(ua.StatusCodes.BadInvalidState)   # paused, resumed or ended meanwhile
        await self._drain()   # the last scan's snapshots are in the inbox: into the nodes before we answer
        await self._sample_every_scan_groups()
        await self._set_runtime("Paused", ua.Variant(True, ua.VariantType.Boolean), self._timestamp(0))
        return [ua.Variant(done, ua.VariantType.UInt64)]

    async def _sample_every_scan_groups(self) -> None:
        """The paused VM's values for the items sampled every scan: their watches read at most
        every FORWARD_S of wall time, so the last scan of a step may not have been read yet."""
        for key in list(self._watches):
            if key[0] == 0 and key[1]:
                await self._fresh(list(key[1]), key)

    async def _method_pause(self, parent):
        self.control.pause()
        deadline = time.monotonic() + 5.0
        while not self.control.paused:
            if time.monotonic() > deadline:
                return ua.StatusCode(ua.StatusCodes.BadTimeout)   # the run is stopped inside a scan
            await asyncio.sleep(0.001)
        await self._drain()
        await self._sample_every_scan_groups()
        await self._set_runtime("Paused", ua.Variant(True, ua.VariantType.Boolean), self._timestamp(0))
        return []

    async def _method_resume(self, parent):
        self.control.resume()
        await self._set_runtime("Paused", ua.Variant(False, ua.VariantType.Boolean), self._timestamp(0))
        return []


def security_plan(config: OpcUaConfig) -> tuple[list, list[type]]:
    """(security policies, identity token kinds) the endpoint offers: SecurityPolicy None and
    anonymous clients only on loopback; Basic256Sha256 whenever a certificate is configured."""
    loopback = config.endpoint.loopback
    policies = [ua.SecurityPolicyType.NoSecurity] if loopback else []
    if config.secure:
        policies += [ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt, ua.SecurityPolicyType.Basic256Sha256_Sign]
    tokens: list[type] = [ua.AnonymousIdentityToken] if loopback else []
    if config.users:
        tokens.append(ua.UserNameIdentityToken)
    if config.trusted_clients:
        tokens.append(ua.X509IdentityToken)
    return policies, tokens


_NOTHING = object()


async def _notify(callback, handle: int, dv: ua.DataValue) -> None:
    try:
        await callback(handle, dv)
    except Exception:   # noqa: BLE001 - one broken subscription must not stop the others
        _log.exception("data change notification failed")


@dataclasses.dataclass
class _ProjectFiles:
    """What `LimitTable.for_project` reads of a project: its manifest and folder."""
    manifest: dict
    root: Any


class _UserManager:
    """Anonymous clients only on loopback; users by password digest; clients by certificate."""

    def __init__(self, config: OpcUaConfig) -> None:
        self.users = dict(config.users)
        self.loopback = config.endpoint.loopback
        self.trusted: dict[bytes, str] = {}
        for path in config.trusted_clients:
            der = path.read_bytes()
            if der.startswith(b"-----BEGIN"):
                der = uacrypto.der_from_x509(uacrypto.x509_from_pem(der))
            self.trusted[der] = path.stem

    def get_user(self, iserver, username=None, password=None, certificate=None):
        kind = _TOKEN_KIND.get()
        if kind == "username":
            digest = self.users.get(username)
            if digest is None or password is None:
                return None
            raw = password if isinstance(password, bytes) else str(password).encode("utf-8")
            if hmac.compare_digest(hashlib.sha256(raw).hexdigest(), digest):
                return User(role=UserRole.User, name=username)
            return None
        if kind == "certificate":
            if not certificate:
                return None
            der = certificate if isinstance(certificate, bytes) else _der(certificate)
            name = self.trusted.get(der)
            return User(role=UserRole.User, name=name) if name is not None else None
        return User(role=UserRole.User, name="anonymous") if self.loopback else None


def _der(certificate) -> bytes:
    return uacrypto.der_from_x509(certificate)


def _free_port(host: str) -> int:
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family, socket.SOCK_STREAM) as probe:
        probe.bind((host, 0))
        return probe.getsockname()[1]


def _index_range_status(text: str) -> int:
    """The status of an IndexRange read on a scalar variable: BadIndexRangeInvalid when the text is
    no NumericRange (OPC UA Part 4 §7.27: `i`, `i:j` with i < j, dimensions joined by commas), else
    BadIndexRangeNoData (§7.27: a valid range that selects nothing; a scalar has no elements)."""
    for part in text.split(","):
        match = re.fullmatch(r"(\d+)(?::(\d+))?", part)
        if match is None or (match.group(2) is not None and int(match.group(2)) <= int(match.group(1))):
            return ua.StatusCodes.BadIndexRangeInvalid
    return ua.StatusCodes.BadIndexRangeNoData


def _arity(method, count: int):
    """`method` called only with its `count` input arguments: asyncua passes whatever the client
    sent, so a wrong count would raise inside the call (Bad_UnexpectedError and a traceback)."""
    async def call(parent, *args):
        if len(args) > count:
            return ua.StatusCode(ua.StatusCodes.BadTooManyArguments)
        if len(args) < count:
            return ua.StatusCode(ua.StatusCodes.BadArgumentsMissing)
        return await method(parent, *args)
    return call


def _os_reason(error: OSError) -> str:
    import errno
    if error.errno == errno.EADDRINUSE:
        return "the port is in use (another server listens there; choose another port: --opcua opc.tcp://HOST:PORT)"
    if error.errno == errno.EADDRNOTAVAIL:
        return "the address is not one of this computer's"
    if error.errno == errno.EACCES:
        return "permission denied (ports below 1024 need privileges)"
    return error.strerror or str(error)


async def _start_listening(server: Server, url: str) -> None:
    """asyncua's `Server.start()` with the bounded transport (stvm.opcua.bounds), and without its
    traceback in the log when the port cannot be bound (start() reports that in one line)."""
    if server.iserver.certificate is not None:
        uacrypto.check_certificate(server.iserver.certificate, server._application_uri, socket.gethostname())
    await server._setup_server_nodes()
    await server.iserver.start()
    try:
        host, port = server._get_bind_socket_info()
        server.bserver = bounds.BoundedBinaryServer(server.iserver, host, port, server.limits)
        server.bserver.set_policies(server._policies)
        await server.bserver.start()
    except BaseException:
        server.bserver = None
        await server.iserver.stop()
        raise


_QUIET = bounds.OneLine()


def _quiet_asyncua() -> None:
    """asyncua's log: errors only (it warns about setups made on purpose, such as no encryption on
    loopback), one line each (no tracebacks for a client's malformed request), rate-limited."""
    log = logging.getLogger("asyncua")
    if log.level == logging.NOTSET:
        log.setLevel(logging.ERROR)
    if not log.handlers:
        handler = logging.StreamHandler()
        handler.setFormatter(logging.Formatter("opcua: %(message)s"))
        handler.addFilter(_QUIET)
        log.addHandler(handler)
        log.propagate = False
