"""Pass 2 of the checker: type resolution (docs/architecture.md, "Checker passes").

`TypeResolver` turns type specifications (`ARRAY[1..N] OF T`, `STRING[20]`, `POINTER TO T`, a
declared name) into `types.Type`s and each TYPE declaration of the index into its type, once
(`ctx.resolved_types`), reporting a type defined in terms of itself. Array bounds and string sizes
are constant expressions: it asks the `ConstantEvaluator`, which asks it back for the types of
SIZEOF operands and initial values, so the two are made together (`Checker.__init__`).
"""

from __future__ import annotations


from stvm.dialects import profile_value
from stvm.semantics import types as t
from stvm.semantics import dialect_rules
from stvm.semantics.context import CheckContext, Pass
from stvm.semantics.limits import array_bounds_problem, array_size_problem
from stvm.settings import StringSize
from stvm.source import is_stdlib_file
from stvm.syntax import nodes as n


def _is_stdlib(file: str) -> bool:
    return is_stdlib_file(file)


class TypeResolver(Pass):
    """Type specifications and TYPE declarations into `types.Type`s (module docstring)."""

    def __init__(self, ctx: CheckContext, indexer) -> None:
        super().__init__(ctx)
        self.indexer = indexer      # index.Indexer: names of enumerators and fields
        self.constants = None       # constants.ConstantEvaluator, which is made with this resolver

    def alias_init(self, spec: n.TypeSpec, namespace: tuple[str, ...], seen: frozenset = frozenset()) -> object:
        """The initial value an alias type declares (`TYPE T : INT := 7;`), for variables of type
        T that have no initialiser of their own; None if there is none."""
        if isinstance(spec, n.SubrangeTypeSpec):
            return spec.low   # IEC 6.4.4.3: a subrange variable starts at its lower bound
        if isinstance(spec, n.ArrayTypeSpec):
            # each element starts at its type's initial value (TcUnit: `ARRAY[1..n] OF UINT(1..m)`
            # starts as n ones); the flat list is what an array initialiser gives
            element = self.alias_init(spec.element, namespace, seen)
            if element is None or any(r is None for r in spec.ranges):
                return None
            ty = self.resolve_type_spec(spec, namespace)
            if not isinstance(ty, t.ArrayType) or not ty.dims:
                return None
            return [element] * ty.length
        if not isinstance(spec, n.NamedTypeSpec):
            return None
        key = self.ctx.index.lookup_type_key(spec.parts, spec.rooted, namespace)
        if key is None or key in seen or not isinstance(self.ctx.index.type_decls[key].body, n.AliasDecl):
            return None  # a cycle is reported by resolve_declared_type
        if key not in self.ctx.resolved_types:
            self.resolve_declared_type(key)   # its own initial value is known once it is resolved
        inits = self.ctx.type_inits.get(key, {})
        if "" in inits:
            return inits[""]
        decl = self.ctx.index.type_decls[key]
        return self.alias_init(decl.body.type_spec, decl.namespace, seen | {key})  # type: ignore[union-attr]

    def resolve_declared_type(self, key: str) -> t.Type | None:
        if key in self.ctx.resolved_types:
            return self.ctx.resolved_types[key]
        decl = self.ctx.index.type_decls[key]
        if key in self.ctx.resolving:
            self.error(f"type '{decl.name}' is defined in terms of itself", decl.span, "E015")
            return None
        self.ctx.resolving.add(key)
        qual = "\\".join(decl.namespace + (decl.name,))
        result: t.Type | None
        body = decl.body
        if isinstance(body, n.EnumDecl):
            members = []
            next_value = 0
            seen = set()
            for name, value, span in body.members:
                self.indexer.check_identifier(name, span)
                if name.lower() in seen:
                    self.error(f"duplicate enumerator '{name}'", span, "E010")
                    continue
                seen.add(name.lower())
                if value is not None:
                    next_value = value
                members.append((name, next_value))
                next_value += 1
            base = t.ELEMENTARY.get((body.base or "INT").upper(), t.INT)
            result = t.EnumType(decl.name, qual, tuple(members), base)
            if body.default is not None:
                if result.value_of(body.default) is None:
                    self.error(f"'{body.default}' is not an enumerator of {decl.name}", body.span, "E016")
                else:
                    result = t.EnumType(decl.name, qual, tuple(members), base, result.value_of(body.default))
            result = dialect_rules.enum_attributes(result, decl.pragmas, self.ctx.settings)   # 'strict', 'to_string'
            for name, value in members:
                self.ctx.enumerators.setdefault(name.lower(), []).append((result, value))
            self.ctx.enums[key] = result
        elif isinstance(body, n.UnionDecl):
            result = self.union_type(key, decl, body, qual)
        elif isinstance(body, n.StructDecl):
            fields: list[tuple[str, t.Type]] = []
            inits: dict[str, object] = {}
            placeholder = t.StructType(decl.name, qual, ())
            self.ctx.resolved_types[key] = placeholder
            for fdecl in body.fields:
                ftype = self.resolve_type_spec(fdecl.type_spec, decl.namespace)
                for fname, fspan in fdecl.names:
                    self.indexer.check_identifier(fname, fspan)
                    if any(f[0].lower() == fname.lower() for f in fields):
                        self.error(f"duplicate field '{fname}' in {decl.name}", fspan, "E010")
                        continue
                    fields.append((fname, ftype or t.DINT))
                    if ftype is not None and fdecl.init is not None:
                        inits[fname.lower()] = self.constants.initial_value(fdecl.init, ftype, decl.namespace, None)
                    elif ftype is not None:
                        alias_value = self.alias_init(fdecl.type_spec, decl.namespace)
                        if alias_value is not None:
                            inits[fname.lower()] = alias_value
            result = t.StructType(decl.name, qual, tuple(fields))
            self.ctx.type_inits[key] = inits
            self.ctx.structs[key] = result
        else:
            result = self.resolve_type_spec(body.type_spec, decl.namespace)
            if result is not None and body.init is not None:
                self.ctx.type_inits[key] = {"": self.constants.initial_value(body.init, result, decl.namespace, None)}
        self.ctx.resolving.discard(key)
        self.ctx.resolved_types[key] = result
        return result

    def union_type(self, key: str, decl: n.TypeDecl, body: n.UnionDecl, qual: str) -> t.UnionType:
        """`TYPE U : UNION … END_UNION`: members of types with a byte image (elementary types,
        enumerations, STRING/WSTRING, arrays and structs of them), without initial values (the
        members share their bytes, which start as zeros)."""
        fields: list[tuple[str, t.Type]] = []
        self.ctx.resolved_types[key] = t.UnionType(decl.name, qual, ())
        for fdecl in body.fields:
            ftype = self.resolve_type_spec(fdecl.type_spec, decl.namespace)
            if fdecl.init is not None:
                self.error(f"a member of UNION {decl.name} has no initial value (the members share "
                           "their bytes)", fdecl.init.span, "E023")
            if ftype is not None and t.byte_size(ftype) is None:
                self.error(f"UNION member of type {ftype.name} has no byte image to overlay (allowed: "
                           "elementary types, enumerations, strings, arrays and structs of them)",
                           fdecl.type_spec.span, "E018")
                ftype = None
            for fname, fspan in fdecl.names:
                self.indexer.check_identifier(fname, fspan)
                if any(f[0].lower() == fname.lower() for f in fields):
                    self.error(f"duplicate member '{fname}' in {decl.name}", fspan, "E010")
                    continue
                fields.append((fname, ftype or t.DINT))
        if not fields:
            self.error(f"UNION {decl.name} has no members", body.span, "E018")
        result = t.UnionType(decl.name, qual, tuple(fields))
        self.ctx.type_inits[key] = {}
        self.ctx.structs[key] = result
        return result

    def open_array_of_rank(self, spec: n.ArrayTypeSpec, element: t.Type) -> t.ArrayType | None:
        """ARRAY[*, *] (IEC ed. 3 6.5.3.2): an open array of several dimensions, each `*`."""
        if any(r is not None for r in spec.ranges):
            self.error("an open array has '*' for every dimension: ARRAY[*, *]", spec.span, "E019")
            return None
        rank = len(spec.ranges)
        return t.ArrayType(f"ARRAY[{', '.join('*' * rank)}] OF {element.name}", element, None, rank)

    def wstring_spec(self, spec: n.StringTypeSpec, namespace: tuple[str, ...]) -> t.Type:
        """WSTRING[n]: n UTF-16 code units (IEC; no NUL counted, unlike Sysmac's STRING[n])."""
        if spec.size is None and not _is_stdlib(spec.span.file) \
                and profile_value(self.ctx.settings.dialect, "unsized_string") == "80 characters":
            return t.wstring_type(80)     # TwinCAT/CODESYS: a WSTRING without a size holds 80
        units = self.constants.const_int(spec.size, namespace)
        if units is None:
            return t.WSTRING
        if not 1 <= units <= t.WSTRING.max_bytes:
            self.error(f"WSTRING size {units} is outside 1..{t.WSTRING.max_bytes}", spec.span, "E019")
            return t.WSTRING
        return t.wstring_type(units)

    def unsized_string(self, span: n.Span) -> t.Type:
        """`STRING` without a size: 1985 characters (Sysmac), or 80 under the profiles whose
        `unsized_string` row says so (TwinCAT, CODESYS); the stdlib's own declarations keep the
        long form (its functions take any STRING)."""
        if _is_stdlib(span.file) or profile_value(self.ctx.settings.dialect, "unsized_string") != "80 characters":
            return t.STRING
        return t.string_type(81, "STRING[80]")

    def resolve_type_spec(self, spec: n.TypeSpec, namespace: tuple[str, ...], allow_generic: bool = False,
                          allow_open_array: bool = False) -> t.Type | None:
        if isinstance(spec, n.NamedTypeSpec):
            if len(spec.parts) == 1:
                upper = spec.parts[0].upper()
                if upper == "STRING":
                    return self.unsized_string(spec.span)
                if upper == "WSTRING" and not _is_stdlib(spec.span.file) \
                        and profile_value(self.ctx.settings.dialect, "unsized_string") == "80 characters":
                    return t.wstring_type(80)
                if upper in t.ELEMENTARY:
                    return t.ELEMENTARY[upper]
                if upper in t.GENERICS:
                    if allow_generic:
                        return t.GENERICS[upper]
                    self.error(f"generic type {upper} is only allowed in library declarations", spec.span, "E017")
                    return None
            key = self.ctx.index.lookup_type_key(spec.parts, spec.rooted, namespace)
            if key is not None:
                return self.resolve_declared_type(key)
            pkey = self.ctx.index.lookup_pou_key(spec.parts, namespace)
            if pkey is not None:
                pou = self.ctx.index.pou_nodes[pkey]
                if pou.kind == "FUNCTION":
                    self.error(f"'{spec.text}' is a function, not a type", spec.span, "E018")
                    return None
                if pou.kind == "INTERFACE":
                    return t.InterfaceType(pou.name, "\\".join(pou.namespace + (pou.name,)))
                return t.FBType(pou.name, "\\".join(pou.namespace + (pou.name,)), pou.kind == "PROGRAM")
            self.error(f"unknown type '{spec.text}'", spec.span, "E018")
            return None
        if isinstance(spec, n.StringTypeSpec) and spec.wide:
            return self.wstring_spec(spec, namespace)
        if isinstance(spec, n.StringTypeSpec):
            if spec.size is None:
                return self.unsized_string(spec.span)
            size = self.constants.const_int(spec.size, namespace)
            if size is None:
                return t.STRING
            if self.ctx.settings.string_size is StringSize.CHARACTERS:
                # IEC ed. 3 / CODESYS / TwinCAT: STRING(n) holds n characters (n + 1 bytes with the NUL)
                if not 1 <= size <= 1985:
                    self.error(f"STRING size {size} is outside 1..1985", spec.span, "E019")
                    return t.STRING
                return t.string_type(size + 1, f"STRING[{size}]")
            if not 1 <= size <= 1986:
                self.error(f"STRING size {size} is outside 1..1986", spec.span, "E019")
                return t.STRING
            return t.string_type(size)
        if isinstance(spec, n.ArrayTypeSpec):
            element = self.resolve_type_spec(spec.element, namespace)
            if element is None:
                return None
            if any(r is None for r in spec.ranges):
                if not allow_open_array:
                    self.error("ARRAY[*] is only allowed for VAR_IN_OUT and inputs of library POUs", spec.span, "E019")
                if len(spec.ranges) > 1:
                    return self.open_array_of_rank(spec, element)
                return t.ArrayType(f"ARRAY[*] OF {element.name}", element, None)
            dims = []
            for lo_expr, hi_expr in spec.ranges:  # type: ignore[misc]
                lo = self.constants.const_int(lo_expr, namespace)
                hi = self.constants.const_int(hi_expr, namespace)
                if lo is None or hi is None:
                    return None
                problem = array_bounds_problem(lo, hi)
                if problem:
                    self.error(problem, spec.span, "E019")
                    return None
                if hi < lo:
                    self.error(f"array bounds {lo}..{hi} are empty", spec.span, "E019")
                    return None
                dims.append((lo, hi))
            problem = array_size_problem(dims, element, self.ctx.settings.max_array_elements)
            if problem:
                self.error(problem, spec.span, "E019")
                return None
            # ARRAY[..] OF ARRAY[..] stays an array of arrays (indexed a[i][j]); a[i, j] needs
            # ARRAY[.., ..]
            text = ",".join(f"{lo}..{hi}" for lo, hi in dims)
            return t.ArrayType(f"ARRAY[{text}] OF {element.name}", element, tuple(dims))
        if isinstance(spec, n.SubrangeTypeSpec):
            base = t.ELEMENTARY.get(spec.base.upper())
            if not isinstance(base, t.IntType):
                self.error(f"subrange base must be an integer type, not {spec.base}", spec.span, "E019")
                return None
            low, high = (b if isinstance(b, int) else self.constants.const_value(b, namespace, None)
                         for b in (spec.low, spec.high))
            if not (isinstance(low, int) and isinstance(high, int)):
                self.error("a subrange bound must be a constant integer expression", spec.span, "E019")
                return base
            if not base.lo <= low <= high <= base.hi:
                self.error(f"subrange {low}..{high} is empty or outside {base.name} ({base.lo}..{base.hi})",
                           spec.span, "E019")
                return base
            return t.subrange_of(base, low, high)
        if isinstance(spec, n.RefTypeSpec):
            target = self.resolve_type_spec(spec.target, namespace)
            if target is None:
                return None
            if isinstance(target, t.RefType) and spec.flavour == "REFERENCE":
                self.error("REFERENCE TO a reference is not allowed", spec.span, "E019")
                return None
            return t.ref_type(target, spec.flavour)
        self.error("unsupported type specification", getattr(spec, "span", n.NO_SPAN), "E019")
        return None
