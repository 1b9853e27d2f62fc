"""The address space: which variables are published (the `[opcua]` rules) and their nodes.

Layout under Objects (namespace `urn:stvm:<project>`, index `ns`):

    Globals                    folder, NodeId s=@Globals
      Cobot                    object (a STRUCT), NodeId s=Cobot
        Connected              variable, NodeId s=Cobot.Connected
      PnP_MoveParameters       object (an ARRAY), NodeId s=PnP_MoveParameters
        [2]                    object, NodeId s=PnP_MoveParameters[2]
          TargetPosition ...   s=PnP_MoveParameters[2].TargetPosition.X
    PnP_Example_Instance       folder (one per program instance), NodeId s=PnP_Example_Instance
      Prg_Step                 variable, s=PnP_Example_Instance.Prg_Step
    Runtime                    object, s=@Runtime: ScanCount, Time, Paused, Clock; Scan(n), Pause, Resume

Every variable's string NodeId is its stvm path (the one `--print` accepts); nodes that are not
variables have an `@` name. Structs, arrays and FB instances are objects whose components are
their members or elements (HasComponent), so a client browses them like the ST declaration.

Variables are created directly as asyncua node records, not through AddNodes: the standard path
costs ~0.5 ms a node (and checks every sibling, quadratic in a folder's size), which would make
the thesis project's ~7,000 variables with FB internals a seconds-long start-up.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterator

from asyncua import ua
from asyncua.server.address_space import AttributeValue, NodeData

from stvm.runtime.catalog import VariableInfo
from stvm.opcua.config import OpcUaConfig, OpcUaConfigError
from stvm.opcua.datatypes import UaType, ua_type
from stvm.semantics import types as t
from stvm.trace.signals import compile_pattern

GLOBALS_ID = "@Globals"
RUNTIME_ID = "@Runtime"
_UNSET = object()


@dataclass(eq=False)
class PublishedVariable:
    """One leaf the server shows: its path, mapping, and the node's Value attribute."""

    info: VariableInfo
    uatype: UaType
    writable: bool
    nodeid: ua.NodeId | None = None
    value_attr: AttributeValue | None = None
    last: Any = field(default=_UNSET, repr=False)   # the last stvm value put into the node

    @property
    def path(self) -> str:
        return self.info.path


@dataclass
class Selection:
    """The published leaves (by path) and the containers that lead to them."""

    variables: dict[str, PublishedVariable]
    containers: set[str]             # paths of struct/array/FB nodes with a published leaf below
    skipped: list[str]               # leaves whose type has no OPC UA mapping (listed at start-up)


# ---------------------------------------------------------------- rules
def _root_kind(root: VariableInfo) -> str:
    return "program" if root.kind == "program" else "global"


def _in_set(name: str, node: VariableInfo, root_kind: str) -> bool:
    if name == "@fb_internals":
        return node.in_fb
    if node.in_fb:
        return False
    if name == "@globals":
        return root_kind == "global"
    if name == "@programs":
        return root_kind == "program" and node.kind != "program"
    if name == "@program_inputs":
        return root_kind == "program" and node.kind != "program" and node.section == "VAR_INPUT"
    raise AssertionError(name)


class _Rules:
    """One list of rules (`publish`, …): sets and path patterns with a hit count each."""

    def __init__(self, key: str, rules: tuple[str, ...]) -> None:
        self.key = key
        self.sets = [r for r in rules if r.startswith("@")]
        self.patterns = [(r, compile_pattern(r)) for r in rules if not r.startswith("@")]
        self.hits = {r: 0 for r, _ in self.patterns}

    def pattern_hit(self, node: VariableInfo) -> bool:
        hit = False
        for text, regex in self.patterns:
            if regex.fullmatch(node.path):
                self.hits[text] += 1
                hit = True
        return hit

    def set_hit(self, node: VariableInfo, root_kind: str) -> bool:
        return any(_in_set(name, node, root_kind) for name in self.sets)

    def check_all_hit(self, what: str) -> None:
        for text, count in self.hits.items():
            if not count:
                raise OpcUaConfigError(f"stvm.toml [opcua] {self.key}: {text!r} matches no {what}")


def select(roots: list[VariableInfo], config: OpcUaConfig) -> Selection:
    """Apply the publish/exclude/writable/read_only rules to the catalog; raises
    OpcUaConfigError for a pattern that matches nothing (a typo would publish silently less)."""
    publish = _Rules("publish", config.publish)
    exclude = _Rules("exclude", config.exclude)
    writable = _Rules("writable", config.writable)
    read_only = _Rules("read_only", config.read_only)
    variables: dict[str, PublishedVariable] = {}
    containers: set[str] = set()
    skipped: list[str] = []

    def visit(node: VariableInfo, root_kind: str, published: bool, excluded: bool, write: bool,
              locked: bool) -> bool:
        """Walk below `node` with the inherited pattern flags; True if a leaf below is published."""
        published = publish.pattern_hit(node) or published
        excluded = exclude.pattern_hit(node) or excluded
        write = writable.pattern_hit(node) or write
        locked = read_only.pattern_hit(node) or locked
        if node.leaf:
            if excluded or not (published or publish.set_hit(node, root_kind)):
                return False
            mapping = ua_type(node.type)
            if mapping is None:
                skipped.append(f"{node.path} ({node.type.name})")
                return False
            can_write = (write or writable.set_hit(node, root_kind)) and not locked and not node.constant
            variables[node.path] = PublishedVariable(node, mapping, can_write)
            return True
        below = False
        for child in node.children:
            below = visit(child, root_kind, published, excluded, write, locked) or below
        if not node.children and (published or publish.set_hit(node, root_kind)) and not excluded \
                and node.kind != "program":
            skipped.append(f"{node.path} ({node.type.name})")   # e.g. an ARRAY too large to list
        if below and node.kind != "program":
            containers.add(node.path)
        return below

    for root in roots:
        visit(root, _root_kind(root), False, False, False, False)
    publish.check_all_hit("variable")
    exclude.check_all_hit("variable")
    writable.check_all_hit("variable")
    read_only.check_all_hit("variable")
    return Selection(variables, containers, skipped)


# ---------------------------------------------------------------- building
_REF_COMPONENT = ua.NodeId(ua.ObjectIds.HasComponent)
_REF_ORGANIZES = ua.NodeId(ua.ObjectIds.Organizes)
_REF_TYPEDEF = ua.NodeId(ua.ObjectIds.HasTypeDefinition)
_REF_PROPERTY = ua.NodeId(ua.ObjectIds.HasProperty)
_PROPERTY_TYPE = ua.NodeId(ua.ObjectIds.PropertyType)
_ANALOG_TYPE = ua.NodeId(ua.ObjectIds.AnalogItemType)
_VARIABLE_TYPE = ua.NodeId(ua.ObjectIds.BaseDataVariableType)
_OBJECT_TYPE = ua.NodeId(ua.ObjectIds.BaseObjectType)


def _dv(value: Any, variant: ua.VariantType, is_array: bool = False) -> ua.DataValue:
    return ua.DataValue(ua.Variant(value, variant, is_array=is_array))


class NodeBuilder:
    """Writes node records into a started-up asyncua address space (server loop thread only).

    Attributes that never change (NodeClass, DataType, access levels, …) share one attribute
    record between all nodes that have the same value, as do the references to a type
    definition and back to a parent: only NodeId, names and Value are per node. Sharing is safe
    because nothing writes those attributes (clients get BadNotWritable, see `server`); a client
    monitoring one of them gets its initial value and never a change."""

    def __init__(self, aspace, ns: int, min_sampling_ms: float) -> None:
        self.aspace = aspace
        self.ns = ns
        read = ua.AccessLevel.CurrentRead.mask
        write = read | ua.AccessLevel.CurrentWrite.mask
        common = {ua.AttributeIds.WriteMask: _dv(0, ua.VariantType.UInt32),
                  ua.AttributeIds.UserWriteMask: _dv(0, ua.VariantType.UInt32)}
        variable = {**common,
                    ua.AttributeIds.NodeClass: _dv(ua.NodeClass.Variable.value, ua.VariantType.Int32),
                    ua.AttributeIds.ValueRank: _dv(-1, ua.VariantType.Int32),
                    ua.AttributeIds.ArrayDimensions: _dv([], ua.VariantType.UInt32, is_array=True),
                    ua.AttributeIds.Historizing: _dv(False, ua.VariantType.Boolean),
                    ua.AttributeIds.MinimumSamplingInterval: _dv(float(min_sampling_ms), ua.VariantType.Double)}
        self._variable = {access: {key: AttributeValue(value) for key, value in
                                   {**variable, ua.AttributeIds.AccessLevel: _dv(level, ua.VariantType.Byte),
                                    ua.AttributeIds.UserAccessLevel: _dv(level, ua.VariantType.Byte)}.items()}
                          for access, level in ((False, read), (True, write))}
        self._object = {key: AttributeValue(value) for key, value in
                        {**common, ua.AttributeIds.NodeClass: _dv(ua.NodeClass.Object.value, ua.VariantType.Int32),
                         ua.AttributeIds.EventNotifier: _dv(0, ua.VariantType.Byte)}.items()}
        self._datatypes: dict[ua.NodeId, AttributeValue] = {}
        self._descriptions: dict[str, AttributeValue] = {}
        self._up: dict[ua.NodeId, ua.ReferenceDescription] = {}
        self._typedef = {
            ua.NodeClass.Variable: ua.ReferenceDescription(
                ReferenceTypeId=_REF_TYPEDEF, IsForward=True, NodeId=_VARIABLE_TYPE,
                BrowseName=ua.QualifiedName("BaseDataVariableType", 0),
                DisplayName=ua.LocalizedText("BaseDataVariableType"), NodeClass=ua.NodeClass.VariableType,
                TypeDefinition=ua.NodeId()),
            ua.NodeClass.Object: ua.ReferenceDescription(
                ReferenceTypeId=_REF_TYPEDEF, IsForward=True, NodeId=_OBJECT_TYPE,
                BrowseName=ua.QualifiedName("BaseObjectType", 0), DisplayName=ua.LocalizedText("BaseObjectType"),
                NodeClass=ua.NodeClass.ObjectType, TypeDefinition=ua.NodeId())}
        self._analog = ua.ReferenceDescription(
            ReferenceTypeId=_REF_TYPEDEF, IsForward=True, NodeId=_ANALOG_TYPE,
            BrowseName=ua.QualifiedName("AnalogItemType", 0), DisplayName=ua.LocalizedText("AnalogItemType"),
            NodeClass=ua.NodeClass.VariableType, TypeDefinition=ua.NodeId())
        self._property_typedef = ua.ReferenceDescription(
            ReferenceTypeId=_REF_TYPEDEF, IsForward=True, NodeId=_PROPERTY_TYPE,
            BrowseName=ua.QualifiedName("PropertyType", 0), DisplayName=ua.LocalizedText("PropertyType"),
            NodeClass=ua.NodeClass.VariableType, TypeDefinition=ua.NodeId())
        self._property = {key: AttributeValue(value) for key, value in
                          {**variable, ua.AttributeIds.AccessLevel: _dv(read, ua.VariantType.Byte),
                           ua.AttributeIds.UserAccessLevel: _dv(read, ua.VariantType.Byte)}.items()}

    def nodeid(self, text: str) -> ua.NodeId:
        return ua.NodeId(text, self.ns)

    def _record(self, nodeid: ua.NodeId, name: str, description: str, constant: dict,
                browse: ua.QualifiedName, display: ua.LocalizedText) -> NodeData:
        data = NodeData(nodeid)
        attrs = data.attributes
        attrs.update(constant)
        attrs[ua.AttributeIds.NodeId] = AttributeValue(_dv(nodeid, ua.VariantType.NodeId))
        attrs[ua.AttributeIds.BrowseName] = AttributeValue(_dv(browse, ua.VariantType.QualifiedName))
        attrs[ua.AttributeIds.DisplayName] = AttributeValue(_dv(display, ua.VariantType.LocalizedText))
        shared = self._descriptions.get(description)
        if shared is None:
            shared = self._descriptions[description] = AttributeValue(
                _dv(ua.LocalizedText(description), ua.VariantType.LocalizedText))
        attrs[ua.AttributeIds.Description] = shared
        return data

    def _link(self, parent: NodeData, child: NodeData, nodeclass: ua.NodeClass, typedef: ua.NodeId,
              browse: ua.QualifiedName, display: ua.LocalizedText, analog: bool = False) -> None:
        parent.references.append(ua.ReferenceDescription(
            ReferenceTypeId=_REF_COMPONENT, IsForward=True, NodeId=child.nodeid, BrowseName=browse,
            DisplayName=display, NodeClass=nodeclass, TypeDefinition=typedef))
        up = self._up.get(parent.nodeid)
        if up is None:
            up = self._up[parent.nodeid] = ua.ReferenceDescription(
                ReferenceTypeId=_REF_COMPONENT, IsForward=False, NodeId=parent.nodeid,
                BrowseName=parent.attributes[ua.AttributeIds.BrowseName].value.Value.Value,
                DisplayName=parent.attributes[ua.AttributeIds.DisplayName].value.Value.Value,
                NodeClass=ua.NodeClass(parent.attributes[ua.AttributeIds.NodeClass].value.Value.Value),
                TypeDefinition=ua.NodeId())
        child.references.append(up)
        child.references.append(self._analog if analog else self._typedef[nodeclass])

    def add_object(self, parent_id: ua.NodeId, path: str, name: str, description: str) -> NodeData:
        browse, display = ua.QualifiedName(name, self.ns), ua.LocalizedText(name)
        data = self._record(self.nodeid(path), name, description, self._object, browse, display)
        self._link(self.aspace[parent_id], data, ua.NodeClass.Object, _OBJECT_TYPE, browse, display)
        self.aspace[data.nodeid] = data
        return data

    def add_variable(self, parent_id: ua.NodeId, var: PublishedVariable, name: str, datatype: ua.NodeId,
                     value: ua.DataValue, analog: bool = False) -> NodeData:
        """`analog`: an AnalogItemType variable (Part 8 §5.3.2: it has an EURange property)."""
        browse, display = ua.QualifiedName(name, self.ns), ua.LocalizedText(name)
        data = self._record(self.nodeid(var.path), name, f"{var.uatype.text} ({var.info.section})",
                            self._variable[var.writable], browse, display)
        shared = self._datatypes.get(datatype)
        if shared is None:
            shared = self._datatypes[datatype] = AttributeValue(_dv(datatype, ua.VariantType.NodeId))
        data.attributes[ua.AttributeIds.DataType] = shared
        var.nodeid = data.nodeid
        var.value_attr = data.attributes[ua.AttributeIds.Value] = AttributeValue(value)
        self._link(self.aspace[parent_id], data, ua.NodeClass.Variable, _ANALOG_TYPE if analog else _VARIABLE_TYPE,
                   browse, display, analog)
        self.aspace[data.nodeid] = data
        return data


    def add_value_variable(self, parent_id: ua.NodeId, array, datatype: ua.NodeId, value: ua.DataValue,
                           description: str) -> NodeData:
        """The variable `<path>.@Value` of an ARRAY object (stvm.opcua.arrays: ValueRank the array's
        rank, ArrayDimensions its lengths, Part 3 §5.6.2) or of a STRUCT object (stvm.opcua.structs:
        a scalar of the struct's DataType)."""
        browse, display = ua.QualifiedName("Value", self.ns), ua.LocalizedText("Value")
        data = self._record(self.nodeid(f"{array.path}.@Value"), "Value", description,
                            self._variable[array.writable], browse, display)
        data.attributes = dict(data.attributes)
        data.attributes[ua.AttributeIds.ValueRank] = AttributeValue(_dv(len(array.dims) or -1, ua.VariantType.Int32))
        data.attributes[ua.AttributeIds.ArrayDimensions] = AttributeValue(
            _dv(list(array.dims), ua.VariantType.UInt32, is_array=True))
        data.attributes[ua.AttributeIds.DataType] = AttributeValue(_dv(datatype, ua.VariantType.NodeId))
        array.nodeid = data.nodeid
        array.value_attr = data.attributes[ua.AttributeIds.Value] = AttributeValue(value)
        self._link(self.aspace[parent_id], data, ua.NodeClass.Variable, _VARIABLE_TYPE, browse, display)
        self.aspace[data.nodeid] = data
        return data

    def add_property(self, parent: NodeData, name: str, variant: ua.Variant, datatype: int) -> NodeData:
        """A read-only property (HasProperty, PropertyType) of `parent`, NodeId `<parent>.@<name>`
        (Part 8: EURange, EngineeringUnits of an AnalogItemType variable)."""
        browse, display = ua.QualifiedName(name, 0), ua.LocalizedText(name)
        nodeid = self.nodeid(f"{parent.nodeid.Identifier}.@{name}")
        data = self._record(nodeid, name, name, self._property, browse, display)
        data.attributes[ua.AttributeIds.DataType] = AttributeValue(_dv(ua.NodeId(datatype, 0), ua.VariantType.NodeId))
        data.attributes[ua.AttributeIds.Value] = AttributeValue(ua.DataValue(variant))
        parent.references.append(ua.ReferenceDescription(
            ReferenceTypeId=_REF_PROPERTY, IsForward=True, NodeId=nodeid, BrowseName=browse,
            DisplayName=display, NodeClass=ua.NodeClass.Variable, TypeDefinition=_PROPERTY_TYPE))
        data.references.append(ua.ReferenceDescription(
            ReferenceTypeId=_REF_PROPERTY, IsForward=False, NodeId=parent.nodeid,
            BrowseName=parent.attributes[ua.AttributeIds.BrowseName].value.Value.Value,
            DisplayName=parent.attributes[ua.AttributeIds.DisplayName].value.Value.Value,
            NodeClass=ua.NodeClass.Variable, TypeDefinition=ua.NodeId()))
        data.references.append(self._property_typedef)
        self.aspace[nodeid] = data
        return data


def walk_published(roots: list[VariableInfo], selection: Selection) -> Iterator[tuple[VariableInfo, VariableInfo | None]]:
    """(node, parent) for every published node below the roots, parents first (root parent: None)."""
    def visit(node: VariableInfo, parent: VariableInfo | None):
        if node.path in selection.variables or node.path in selection.containers:
            yield node, parent
            for child in node.children:
                yield from visit(child, node)
    for root in roots:
        if root.kind == "program":
            for child in root.children:
                yield from visit(child, root)
        else:
            yield from visit(root, None)


def describe(node: VariableInfo) -> str:
    ty = node.type
    if isinstance(ty, t.ArrayType):
        dims = ", ".join(f"{lo}..{hi}" for lo, hi in ty.dims or ())
        return f"ARRAY[{dims}] OF {ty.element.name} ({node.section})"
    return f"{ty.name} ({node.section})"
