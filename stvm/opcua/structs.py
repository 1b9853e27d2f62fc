"""Structured DataTypes for ST STRUCTs, and a variable per struct instance whose Value is the struct.

For every ST STRUCT type a published struct instance has (OPC UA Part 3 §8.48 StructureDefinition,
Part 5 §12.2 the Structure type, Part 6 §5.2.6 ExtensionObject encoding):

* a DataType node `ns;s=@Type.<type name>` (BrowseName the ST name), a subtype of Structure, with
  a DataTypeDefinition (StructureDefinition: one field per member, in declaration order, its
  DataType the member's: an elementary type, an enum's own DataType, another STRUCT's DataType;
  a one-dimensional ARRAY member is the element type with ValueRank 1 and ArrayDimensions [n]);
* its "Default Binary" encoding node `@Type.<type name>.@Binary` (HasEncoding), the ExtensionObject's
  TypeId on the wire; asyncua's client builds the Python class from the definition
  (`await client.load_data_type_definitions()`).

Every struct instance whose members are all published gets, beside today's object of member
variables, the variable `ns;s=<path>.@Value` (BrowseName `Value`, a component of the struct's
object) whose Value is the ExtensionObject. A struct with a member that has no OPC UA mapping
(a pointer, an FB, a multi-dimensional array) gets no DataType and no such variable.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields as dataclass_fields
from typing import Any, Callable, Iterator

from asyncua import ua
from asyncua.common.structures104 import make_enum, make_structure

from stvm.opcua.datatypes import ua_type
from stvm.opcua.nodes import PublishedVariable
from stvm.semantics import types as t


@dataclass(eq=False)
class PublishedStruct:
    """One struct instance served as an ExtensionObject variable."""

    path: str
    elements: list[PublishedVariable]     # its leaves, in declaration order (nested structs, arrays flattened)
    type_key: str
    writable: bool
    build: Callable[[Iterator[Any]], Any] = field(repr=False)     # leaf values → the Python struct
    split: Callable[[Any], list[Any]] = field(repr=False)         # the Python struct → leaf Variant values
    nodeid: ua.NodeId | None = None
    value_attr: Any = None
    last: tuple | None = field(default=None, repr=False)
    dims: tuple = ()

    @property
    def paths(self) -> list[str]:
        return [e.path for e in self.elements]

    def variant(self, values) -> ua.Variant:
        return ua.Variant(self.build(iter(values)), ua.VariantType.ExtensionObject)


class StructTypes:
    """The DataType nodes and Python classes of the STRUCT types served (server loop only)."""

    def __init__(self, ns: int, enum_types: dict[str, ua.NodeId]) -> None:
        self.ns = ns
        self.enum_types = enum_types
        self.classes: dict[str, type] = {}           # type key → asyncua dataclass
        self.datatypes: dict[str, ua.NodeId] = {}
        self._order: list[tuple[str, t.StructType]] = []
        self._refused: set[str] = set()

    @staticmethod
    def key(ty: t.StructType) -> str:
        return ty.qualname or ty.name

    def want(self, ty: t.StructType) -> bool:
        """Collect `ty` and the STRUCTs it uses (inner first); False if a member cannot be mapped."""
        key = self.key(ty)
        if key in self.classes or any(k == key for k, _ in self._order):
            return True
        if key in self._refused:
            return False
        for _, member in ty.fields:
            if not self._member_ok(member):
                self._refused.add(key)
                return False
        self._order.append((key, ty))
        return True

    def _member_ok(self, member: t.Type) -> bool:
        if isinstance(member, t.ArrayType):
            return len(member.dims) == 1 and not isinstance(member.element, t.ArrayType) and \
                self._member_ok(member.element)
        if isinstance(member, t.StructType):
            return self.want(member)
        return ua_type(member) is not None

    def _field_type(self, member: t.Type) -> ua.NodeId:
        if isinstance(member, t.StructType):
            return self.datatypes[self.key(member)]
        if isinstance(member, t.EnumType):
            return self._enum_class(member)[0]
        return ua_type(member).datatype

    def _enum_class(self, member: t.EnumType) -> tuple[ua.NodeId, type | None]:
        """The enum's DataType and its Python class (made once: the struct classes refer to it)."""
        dtype = self.enum_types.get(member.qualname or member.name)
        if dtype is None:
            return ua.NodeId(ua.ObjectIds.Int32), None
        cls = ua.enums_by_datatype.get(dtype)
        if cls is None:
            definition = ua.EnumDefinition(Fields=[ua.EnumField(Name=name, Value=value)
                                                   for name, value in member.members])
            cls = make_enum(member.name, definition, False)[member.name]
            ua.register_enum(member.name, dtype, cls)
        return dtype, cls

    async def build(self, server) -> None:
        """DataType, encoding and definition nodes, then the Python classes, inner types first."""
        structure = server.nodes.base_structure_type
        for key, ty in self._order:
            dtype_id = ua.NodeId(f"@Type.{key}", self.ns)
            encoding_id = ua.NodeId(f"@Type.{key}.@Binary", self.ns)
            dtype = await structure.add_data_type(dtype_id, ua.QualifiedName(ty.name, self.ns))
            await _add_encoding(server, dtype_id, encoding_id)
            definition = ua.StructureDefinition(
                DefaultEncodingId=encoding_id, BaseDataType=structure.nodeid,
                StructureType=ua.StructureType.Structure, Fields=[])
            for name, member in ty.fields:
                element = member.element if isinstance(member, t.ArrayType) else member
                struct_field = ua.StructureField(Name=name, Description=ua.LocalizedText(member.name),
                                                 DataType=self._field_type(element), IsOptional=False)
                if isinstance(member, t.ArrayType):
                    lo, hi = member.dims[0]
                    struct_field.ValueRank = 1
                    struct_field.ArrayDimensions = [hi - lo + 1]
                else:
                    struct_field.ValueRank = -1
                definition.Fields.append(struct_field)
            await dtype.write_data_type_definition(definition)
            self.datatypes[key] = dtype_id
            cls = make_structure(dtype_id, ty.name, definition)[ty.name]
            cls.data_type = dtype_id
            ua.register_extension_object(ty.name, encoding_id, cls, dtype_id)
            self.classes[key] = cls

    # ---------------------------------------------------------------- values
    def builder(self, ty: t.StructType) -> Callable[[Iterator[Any]], Any]:
        """A function making the Python struct from an iterator over the leaf values (stvm values)."""
        cls = self.classes[self.key(ty)]
        parts = [self._member_builder(member) for _, member in ty.fields]
        names = [f.name for f in dataclass_fields(cls) if f.name != "Encoding"]

        def build(values: Iterator[Any]) -> Any:
            return cls(**{name: part(values) for name, part in zip(names, parts)})
        return build

    def _member_builder(self, member: t.Type) -> Callable[[Iterator[Any]], Any]:
        if isinstance(member, t.StructType):
            return self.builder(member)
        if isinstance(member, t.ArrayType):
            lo, hi = member.dims[0]
            one = self._member_builder(member.element)
            return lambda values: [one(values) for _ in range(hi - lo + 1)]
        to_ua = ua_type(member).to_ua
        if isinstance(member, t.EnumType):
            _, cls = self._enum_class(member)
            known = {value for _, value in member.members}
            if cls is not None:
                return lambda values: (lambda v: cls(v) if v in known else v)(to_ua(next(values)))
        return lambda values: to_ua(next(values))

    def splitter(self, ty: t.StructType) -> Callable[[Any], list[Any]]:
        """A function giving the leaf values (as OPC UA values) of a Python struct a client wrote;
        raises TypeError/ValueError for a value that is not one."""
        cls = self.classes[self.key(ty)]
        parts = [self._member_splitter(member) for _, member in ty.fields]
        names = [f.name for f in dataclass_fields(cls) if f.name != "Encoding"]

        def split(value: Any) -> list[Any]:
            if not isinstance(value, cls):
                raise TypeError(f"expected {ty.name}, got {type(value).__name__}")
            out: list[Any] = []
            for name, part in zip(names, parts):
                out.extend(part(getattr(value, name)))
            return out
        return split

    def _member_splitter(self, member: t.Type) -> Callable[[Any], list[Any]]:
        if isinstance(member, t.StructType):
            return self.splitter(member)
        if isinstance(member, t.ArrayType):
            lo, hi = member.dims[0]
            one = self._member_splitter(member.element)

            def split_array(value: Any) -> list[Any]:
                if not isinstance(value, list) or len(value) != hi - lo + 1:
                    raise ValueError(f"expected {hi - lo + 1} elements")
                out: list[Any] = []
                for item in value:
                    out.extend(one(item))
                return out
            return split_array
        return lambda value: [int(value) if isinstance(member, t.EnumType) else value]


def find_structs(roots, variables: dict[str, PublishedVariable], types: StructTypes) -> list[tuple[Any, t.StructType]]:
    """(catalog node, type) for every struct instance whose leaves are all published and whose
    type maps; the types are collected into `types`."""
    found = []
    for root in roots:
        for node in root.walk():
            if not isinstance(node.type, t.StructType) or not node.children:
                continue
            leaves = _leaves(node)
            if not leaves or any(leaf.path not in variables for leaf in leaves):
                continue
            if types.want(node.type):
                found.append((node, node.type))
    return found


def _leaves(node) -> list:
    if not node.children:
        return [node]
    out = []
    for child in node.children:
        out.extend(_leaves(child))
    return out


def published_struct(node, ty: t.StructType, variables: dict[str, PublishedVariable],
                     types: StructTypes) -> PublishedStruct:
    elements = [variables[leaf.path] for leaf in _leaves(node)]
    return PublishedStruct(node.path, elements, types.key(ty), all(e.writable for e in elements),
                           types.builder(ty), types.splitter(ty))


async def _add_encoding(server, dtype_id: ua.NodeId, encoding_id: ua.NodeId) -> None:
    item = ua.AddNodesItem(
        RequestedNewNodeId=encoding_id, BrowseName=ua.QualifiedName("Default Binary", 0),
        NodeClass=ua.NodeClass.Object, ParentNodeId=dtype_id, ReferenceTypeId=ua.NodeId(ua.ObjectIds.HasEncoding),
        TypeDefinition=ua.NodeId(ua.ObjectIds.DataTypeEncodingType),
        NodeAttributes=ua.ObjectAttributes(DisplayName=ua.LocalizedText("Default Binary")))
    (await server.iserver.isession.add_nodes([item]))[0].StatusCode.check()
