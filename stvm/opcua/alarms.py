"""OPC UA Alarms & Conditions (Part 9) over the one alarm list of the VM (`stvm.frontend.alarms`).

Every alarm source of the HMI's list (an FB instance with an `Error` output, and the VM's fault)
is one condition of type `AlarmConditionType`:

* the source's object (`ns;s=<FB path>`, the FB instance's own NodeId; under `Objects/Alarms` when
  the FB's internals are not published) emits the condition's events; so does the Server object
  (a SCADA's alarm view subscribes there). The VM's fault is emitted by `@Runtime` and the Server.
* the condition node `ns;s=<FB path>.@Error` (ConditionName `Error`; `@Runtime.@Fault` for the VM)
  is the ObjectId that Acknowledge is called on; the source has a HasCondition reference to it.
  Its state is carried by its events (Part 9 lets a server keep condition instances out of the
  address space; this one keeps only the node, so its state variables are not nodes to read).
* an event is sent at every change of the HMI's alarm: raised (ActiveState true, AckedState
  false, Retain true), ErrorID/text changed, returned (ActiveState false), acknowledged (from
  OPC UA, the HMI or the API: the list is shared). Retain stays true while the alarm is active or
  unacknowledged (Part 9 §5.5.2).
* `Acknowledge(EventId, Comment)` acknowledges the alarm in the shared list (the HMI's row goes
  too); `ConditionRefresh(SubscriptionId)` re-sends the retained conditions between
  RefreshStartEvent and RefreshEndEvent to that subscription's event items (Part 9 §5.5.7).

Choices: AlarmConditionType rather than OffNormalAlarmType (an FB's Error is a fault, not a
deviation from a configured normal state; OffNormalAlarmType would need a NormalState variable
with nothing to point to). ConditionClass Process for FB errors, System for the VM's fault.
Time is the VM clock of the scan that made the change (virtual time on the virtual clock), as for
data changes. Message is the FB's ErrorDescrip with its ErrorID (`Robot not connected
(ErrorID 16#0099)`).
"""

from __future__ import annotations

import asyncio
import copy
import logging
import uuid
from typing import Any

from asyncua import ua
from asyncua.common.event_objects import AlarmCondition, RefreshEndEvent, RefreshStartEvent

from stvm.frontend.alarms import Alarm, AlarmList
from stvm.opcua.nodes import RUNTIME_ID

ALARMS_ID = "@Alarms"
VM_SOURCE = "VM"
FAULT_POLL_S = 0.5          # how often the server looks for a VM fault (the scan loop has stopped)
MAX_EVENT_IDS = 1000        # EventIds Acknowledge accepts (the newest ones)
_log = logging.getLogger("stvm.opcua")
_SERVER = ua.NodeId(ua.ObjectIds.Server)
_UTC = ua.VariantType.DateTime


class _Condition:
    """One alarm source as a condition: its nodes and its last event."""

    def __init__(self, source: str, source_node: ua.NodeId, condition_node: ua.NodeId, name: str,
                 input_node: ua.NodeId | None, system: bool) -> None:
        self.source = source
        self.source_node = source_node
        self.condition_node = condition_node
        self.name = name
        self.input_node = input_node
        self.system = system
        self.alarm: Alarm | None = None
        self.event: AlarmCondition | None = None     # the newest event (ConditionRefresh sends it)
        self.active_since = None
        self.acked_since = None
        self.comment = ""                           # the last Acknowledge's comment (Part 9 §5.5.2 Comment)


class AlarmConditions:
    """The conditions of one server; built in the server loop, fed by the shared alarm list."""

    def __init__(self, owner: Any, alarms: AlarmList) -> None:
        # owner: the OpcUaServer (its ns, variables, VM clock, asyncua server)
        self.owner = owner
        self.alarms = alarms
        self.conditions: dict[str, _Condition] = {}              # source path → condition
        self._by_node: dict[ua.NodeId, _Condition] = {}          # condition NodeId → condition
        self._event_ids: dict[bytes, tuple[str, int]] = {}        # EventId → (source, alarm id)
        self._unsubscribe = None
        self._poll: asyncio.Task | None = None

    # ------------------------------------------------------------------ building
    async def build(self, server) -> None:
        owner, ns = self.owner, self.owner.ns
        aspace = server.iserver.aspace
        folder = None
        for source in self.alarms.sources:
            source_id = ua.NodeId(source.path, ns)
            if source_id not in aspace:
                if folder is None:
                    folder = await server.nodes.objects.add_folder(ua.NodeId(ALARMS_ID, ns),
                                                                   ua.QualifiedName("Alarms", ns))
                obj = await folder.add_object(source_id, ua.QualifiedName(source.path, ns))
                await obj.write_attribute(ua.AttributeIds.Description, ua.DataValue(ua.Variant(
                    ua.LocalizedText(f"{source.fb_type} instance (its alarms)"), ua.VariantType.LocalizedText)))
            error_var = owner.variables.get(source.error)
            await self._add(server, source.path, source_id, "Error",
                            error_var.nodeid if error_var is not None else None, system=False)
        runtime_id = ua.NodeId(RUNTIME_ID, ns)
        await self._add(server, VM_SOURCE, runtime_id, "Fault", None, system=True)
        session = server.iserver.isession
        session.add_method_callback(ua.NodeId(ua.ObjectIds.AcknowledgeableConditionType_Acknowledge),
                                    self._acknowledge)
        for method in (ua.ObjectIds.ConditionType_ConditionRefresh, ua.ObjectIds.ConditionType_ConditionRefresh2):
            session.add_method_callback(ua.NodeId(method), self._condition_refresh)
        for alarm in self.alarms.current():     # alarms raised before the server started
            await self._emit(alarm, self.owner.vm.now_ns)

    async def _add(self, server, source: str, source_id: ua.NodeId, name: str, input_node, system: bool) -> None:
        ns = self.owner.ns
        source_node = server.get_node(source_id)
        await source_node.set_event_notifier([ua.EventNotifier.SubscribeToEvents])
        condition_id = ua.NodeId(f"{source_id.Identifier}.@{name}", ns)
        item = ua.AddNodesItem(
            RequestedNewNodeId=condition_id, BrowseName=ua.QualifiedName(name, ns),
            NodeClass=ua.NodeClass.Object, ParentNodeId=source_id,
            ReferenceTypeId=ua.NodeId(ua.ObjectIds.HasComponent),
            TypeDefinition=ua.NodeId(ua.ObjectIds.AlarmConditionType),
            NodeAttributes=ua.ObjectAttributes(DisplayName=ua.LocalizedText(name), EventNotifier=0))
        session = server.iserver.isession
        (await session.add_nodes([item]))[0].StatusCode.check()
        refs = [ua.AddReferencesItem(SourceNodeId=source_id, ReferenceTypeId=ua.NodeId(ua.ObjectIds.HasCondition),
                                     IsForward=True, TargetNodeId=condition_id, TargetNodeClass=ua.NodeClass.Object),
                ua.AddReferencesItem(SourceNodeId=_SERVER, ReferenceTypeId=ua.NodeId(ua.ObjectIds.HasNotifier),
                                     IsForward=True, TargetNodeId=source_id, TargetNodeClass=ua.NodeClass.Object),
                ua.AddReferencesItem(SourceNodeId=source_id, ReferenceTypeId=ua.NodeId(ua.ObjectIds.GeneratesEvent),
                                     IsForward=True, TargetNodeId=ua.NodeId(ua.ObjectIds.AlarmConditionType),
                                     TargetNodeClass=ua.NodeClass.ObjectType)]
        for result in await session.add_references(refs):
            result.check()
        condition = _Condition(source, source_id, condition_id, name, input_node, system)
        self.conditions[source] = condition
        self._by_node[condition_id] = condition

    def start(self, loop: asyncio.AbstractEventLoop) -> None:
        """Listen to the shared list (any thread hands the alarm to the loop) and poll for a VM fault."""
        vm = self.owner.vm

        def listener(alarm: Alarm) -> None:
            now_ns = vm.now_ns            # the thread that changed it: the VM's (raise/return) or ours
            try:
                loop.call_soon_threadsafe(lambda: asyncio.ensure_future(self._emit(alarm, now_ns)))
            except RuntimeError:          # the loop is closing: the run ends
                pass
        self._unsubscribe = self.alarms.subscribe(listener)
        self._poll = loop.create_task(self._poll_fault())

    def stop(self) -> None:
        if self._unsubscribe is not None:
            self._unsubscribe()
            self._unsubscribe = None
        if self._poll is not None:
            self._poll.cancel()
        self.alarms.close()

    async def _poll_fault(self) -> None:
        vm = self.owner.vm
        while True:
            await asyncio.sleep(FAULT_POLL_S)
            self.alarms.poll_vm(vm)

    # ------------------------------------------------------------------ events
    async def _emit(self, alarm: Alarm, now_ns: int) -> None:
        condition = self.conditions.get(alarm.source)
        if condition is None:
            return
        previous = condition.alarm
        if previous is not None and previous.id > alarm.id:
            return                        # a late notice of an alarm already superseded
        stamp = self.owner._timestamp(now_ns)
        if previous is not None and previous.id != alarm.id:
            condition.comment = ""        # a new alarm of this source starts without a comment
        if previous is None or previous.id != alarm.id or previous.active != alarm.active:
            condition.active_since = self.owner._timestamp(alarm.raised_vm_ns) if alarm.active and \
                (previous is None or previous.id != alarm.id) else stamp
        if previous is None or previous.id != alarm.id or previous.acknowledged != alarm.acknowledged:
            condition.acked_since = stamp
        condition.alarm = alarm
        event = self._event(condition, alarm, stamp)
        condition.event = event
        self._event_ids[event.EventId] = (alarm.source, alarm.id)
        while len(self._event_ids) > MAX_EVENT_IDS:
            del self._event_ids[next(iter(self._event_ids))]
        await self._send(event, condition.source_node)

    def _event(self, condition: _Condition, alarm: Alarm, stamp) -> AlarmCondition:
        event = AlarmCondition()
        fields = {
            "EventId": (uuid.uuid4().bytes, ua.VariantType.ByteString),
            "SourceNode": (condition.source_node, ua.VariantType.NodeId),
            "SourceName": (alarm.source, ua.VariantType.String),
            "Time": (stamp, _UTC),
            "ReceiveTime": (stamp, _UTC),
            "Message": (ua.LocalizedText(message_of(alarm)), ua.VariantType.LocalizedText),
            "Severity": (alarm.severity, ua.VariantType.UInt16),
            "LastSeverity": (alarm.severity, ua.VariantType.UInt16),
            "ConditionClassId": (ua.NodeId(ua.ObjectIds.SystemConditionClassType if condition.system
                                           else ua.ObjectIds.ProcessConditionClassType), ua.VariantType.NodeId),
            "ConditionClassName": (ua.LocalizedText("System" if condition.system else "Process"),
                                   ua.VariantType.LocalizedText),
            "ConditionName": (condition.name, ua.VariantType.String),
            "BranchId": (ua.NodeId(), ua.VariantType.NodeId),
            "Retain": (alarm.active or not alarm.acknowledged, ua.VariantType.Boolean),
            "EnabledState": (ua.LocalizedText("Enabled"), ua.VariantType.LocalizedText),
            "EnabledState/Id": (True, ua.VariantType.Boolean),
            "Quality": (ua.StatusCode(ua.StatusCodes.Good), ua.VariantType.StatusCode),
            "ActiveState": (ua.LocalizedText("Active" if alarm.active else "Inactive"), ua.VariantType.LocalizedText),
            "ActiveState/Id": (alarm.active, ua.VariantType.Boolean),
            "ActiveState/TransitionTime": (condition.active_since, _UTC),
            "AckedState": (ua.LocalizedText("Acknowledged" if alarm.acknowledged else "Unacknowledged"),
                           ua.VariantType.LocalizedText),
            "AckedState/Id": (alarm.acknowledged, ua.VariantType.Boolean),
            "AckedState/TransitionTime": (condition.acked_since, _UTC),
            "SuppressedOrShelved": (False, ua.VariantType.Boolean),
            "Comment": (ua.LocalizedText(condition.comment), ua.VariantType.LocalizedText),
            "InputNode": (condition.input_node or ua.NodeId(), ua.VariantType.NodeId),
            "NodeId": (condition.condition_node, ua.VariantType.NodeId),   # the ConditionId
        }
        for name, (value, variant) in fields.items():
            event.add_property(name, value, variant)
        event.emitting_node = condition.source_node
        return event

    async def _send(self, event, source_node: ua.NodeId) -> None:
        """To the items monitoring the source's object and to those monitoring the Server."""
        service = self.owner._server.iserver.subscription_service
        for emitting in (source_node, _SERVER):
            copy_ = copy.copy(event)
            copy_.emitting_node = emitting
            for sub in list(service.subscriptions.values()):
                try:
                    await sub.monitored_item_srv.trigger_event(copy_)
                except Exception:   # noqa: BLE001 - one broken subscription must not stop the others
                    _log.exception("event notification failed")

    # ------------------------------------------------------------------ methods
    async def _acknowledge(self, parent: ua.NodeId, event_id=None, comment=None, *extra):
        """AcknowledgeableConditionType.Acknowledge on the condition `parent` (Part 9 §5.7.3)."""
        if extra:
            return ua.StatusCode(ua.StatusCodes.BadTooManyArguments)
        if event_id is None or comment is None:
            return ua.StatusCode(ua.StatusCodes.BadArgumentsMissing)
        event_id = event_id.Value if isinstance(event_id, ua.Variant) else event_id
        condition = self._by_node.get(parent)
        if condition is None:
            return ua.StatusCode(ua.StatusCodes.BadNodeIdInvalid)     # not one of our conditions
        if not isinstance(event_id, bytes):
            return ua.StatusCode(ua.StatusCodes.BadTypeMismatch)
        known = self._event_ids.get(event_id)
        if known is None or known[0] != condition.source:
            return ua.StatusCode(ua.StatusCodes.BadEventIdUnknown)
        current = {alarm.id: alarm for alarm in self.alarms.current()}
        alarm = current.get(known[1])
        if alarm is None or alarm.acknowledged:
            # acknowledged already (here, in the HMI) or returned and acknowledged: nothing to do
            return ua.StatusCode(ua.StatusCodes.BadConditionBranchAlreadyAcked)
        text = comment.Value if isinstance(comment, ua.Variant) else comment
        condition.comment = (text.Text if isinstance(text, ua.LocalizedText) else str(text or "")) or ""
        self.alarms.acknowledge(alarm.id)     # the listener sends the AckedState event
        return []

    async def _condition_refresh(self, parent: ua.NodeId, subscription_id=None, item_id=None, *extra):
        """ConditionRefresh(SubscriptionId) and ConditionRefresh2(SubscriptionId, MonitoredItemId):
        the retained conditions again, to that subscription's event items (or the one item),
        between a RefreshStartEvent and a RefreshEndEvent (Part 9 §5.5.7, §5.5.8). The two markers
        bypass the items' where clauses and carry one EventId each (Part 9 §4.5); the conditions
        pass the where clause as any event does."""
        if extra:
            return ua.StatusCode(ua.StatusCodes.BadTooManyArguments)
        if subscription_id is None:
            return ua.StatusCode(ua.StatusCodes.BadArgumentsMissing)
        sub_id = subscription_id.Value if isinstance(subscription_id, ua.Variant) else subscription_id
        mid = item_id.Value if isinstance(item_id, ua.Variant) else item_id
        service = self.owner._server.iserver.subscription_service
        sub = service.subscriptions.get(sub_id) if isinstance(sub_id, int) else None
        if sub is None:
            return ua.StatusCode(ua.StatusCodes.BadSubscriptionIdInvalid)
        items = sub.monitored_item_srv
        watched = [(node, m) for node, mids in items._monitored_events.items() for m in mids
                   if mid is None or m == mid]
        if mid is not None and not watched:
            return ua.StatusCode(ua.StatusCodes.BadMonitoredItemIdInvalid)
        stamp = self.owner._timestamp(self.owner.vm.now_ns)
        start, end = _marker(RefreshStartEvent(), stamp), _marker(RefreshEndEvent(), stamp)
        for _, m in watched:
            await _enqueue_unfiltered(items, start, m)
        for node, m in watched:
            for condition in self.conditions.values():
                event = condition.event
                if event is None or not event.Retain or node not in (condition.source_node, _SERVER):
                    continue
                event = copy.copy(event)
                event.emitting_node = node
                await items._trigger_event(event, m)
        for _, m in watched:
            await _enqueue_unfiltered(items, end, m)
        return []


async def _enqueue_unfiltered(items, event, mid: int) -> None:
    data = items._monitored_items.get(mid)
    if data is None:
        return
    fields = ua.EventFieldList(ClientHandle=data.client_handle,
                               EventFields=event.to_event_fields(data.filter.SelectClauses))
    await items.isub.enqueue_event(mid, fields, data.queue_size)


def _marker(event, stamp):
    event.EventId = uuid.uuid4().bytes
    event.SourceNode = _SERVER
    event.SourceName = "Server"
    event.Time = event.ReceiveTime = stamp
    event.Severity = 1
    return event


def message_of(alarm: Alarm) -> str:
    """The event's Message: the FB's text with its ErrorID, as the HMI's list shows them."""
    text = alarm.text or f"{alarm.fb_type} error"
    if alarm.code is None:
        return text
    return f"{text} (ErrorID 16#{alarm.code:04X})"
