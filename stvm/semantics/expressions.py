"""Pass 4 of the checker, the body checks (docs/architecture.md, "Checker passes"), one part.
Expressions: literals, names, indexing, dereferences, unary and binary operators. Made by
`body.BodyChecker`, one per checked body; the other parts, the walk's state and the hooks the
debugger overrides are reached through `self.bc` (bodypart.py).
"""

from __future__ import annotations

from stvm.semantics import types as t
from stvm.semantics import dialect_rules
from stvm.numeric import utf16_units
from stvm.semantics.facts import NOT_CONST, NameRef
from stvm.semantics.model import Variable
from stvm.syntax import nodes as n
from stvm.semantics.typing_rules import (
    COMPARE_OPS, LOGIC_OPS, OP_TEXT, int_literal_type, common_int, real_for)
from stvm.semantics.bodypart import BodyPart


class ExpressionTyper(BodyPart):
    """Expressions: literals, names, indexing, dereferences, unary and binary operators."""

    def expr_AssignExpr(self, e: n.AssignExpr, expected) -> t.Type | None:
        return dialect_rules.check_assign_expr(self.bc, e)   # CODESYS/TwinCAT `(x := v)`

    def expr_IntLiteral(self, e: n.IntLiteral, expected) -> t.Type:
        self.facts.untyped.add(e.nid)
        self.facts.consts[e.nid] = e.value
        return int_literal_type(e.value, self.settings)

    def expr_RealLiteral(self, e: n.RealLiteral, expected) -> t.Type:
        self.facts.untyped.add(e.nid)
        self.facts.consts[e.nid] = e.value
        return t.LREAL

    def expr_BoolLiteral(self, e, expected) -> t.Type:
        self.facts.consts[e.nid] = e.value
        return t.BOOL

    def expr_StringLiteral(self, e: n.StringLiteral, expected) -> t.Type:
        if isinstance(e.value, str) or t.is_wide(expected):
            return self.wstring_literal(e)
        self.facts.consts[e.nid] = e.value
        return t.string_type(max(len(e.value) + 1, 1))

    def wstring_literal(self, e: n.StringLiteral) -> t.Type:
        """A WSTRING literal ("…"), or a STRING literal where a WSTRING is expected (CODESYS takes
        `ws := 'abc'`): its value is the `str` of its UTF-16 code units."""
        value = e.value if isinstance(e.value, str) else utf16_units(e.value.decode("utf-8", "replace"))
        self.facts.consts[e.nid] = value
        return t.wstring_type(max(len(value), 1))

    def expr_TimeLiteral(self, e: n.TimeLiteral, expected) -> t.Type:
        self.facts.consts[e.nid] = e.value_ns
        return t.ELEMENTARY[e.type_name]

    def expr_HashLiteral(self, e: n.HashLiteral, expected) -> t.Type | None:
        lit = self.c.constants.hash_literal(e, self.pou_namespace)
        if lit is None:
            return None
        self.facts.consts[e.nid] = lit[1]
        return lit[0]

    def expr_Name(self, e: n.Name, expected) -> t.Type | None:
        ref = self.bc.resolve_name(e)
        if ref is None:
            if len(e.parts) == 1 and isinstance(expected, t.EnumType) and expected.value_of(e.parts[0]) is not None:
                ref = NameRef("enum", value=expected.value_of(e.parts[0]), variable=Variable(e.parts[0], "ENUM", expected))
            elif len(e.parts) == 1 and not e.rooted and e.parts[0].upper() == "NULL":
                self.facts.names[e.nid] = NameRef("null")  # type: ignore[assignment]
                return t.NULL_REF
            elif len(e.parts) == 1 and not e.rooted and e.parts[0].upper() in ("THIS", "SUPER"):
                return self.bc.members.this_or_super(e)
            else:
                self.bc.members.undeclared(e)
                return None
        self.facts.names[e.nid] = ref  # type: ignore[assignment]
        if ref.kind == "enum":  # type: ignore[attr-defined]
            self.facts.consts[e.nid] = ref.value  # type: ignore[attr-defined]
            return ref.variable.type  # type: ignore[attr-defined]
        if ref.kind == "result":  # type: ignore[attr-defined]
            return self.implicit_deref(e, self.pou.return_type) if self.pou.return_type is not None else None
        if ref.kind == "prop":  # type: ignore[attr-defined]
            return self.bc.members.property_load(e, ref.value, "self")  # type: ignore[attr-defined]
        var: Variable = ref.variable  # type: ignore[attr-defined]
        if var.constant and var.init is not None and not isinstance(var.init, (list, dict)):
            self.facts.consts[e.nid] = var.init
        return self.implicit_deref(e, var.type)

    def expr_BitAccess(self, e: n.BitAccess, expected) -> t.Type | None:
        base = self.bc.expr(e.base)
        if base is None:
            return None
        if not isinstance(base, t.IntType):
            self.error(f"bit access needs an integer or bit string, not {base.name}", e.span, "E035")
            return None
        if not 0 <= e.bit < base.bits:
            self.error(f"bit {e.bit} is outside {base.name} (0..{base.bits - 1})", e.span, "E035")
            return None
        return t.BOOL

    def expr_PartialAccess(self, e: n.PartialAccess, expected) -> t.Type | None:
        base = self.bc.expr(e.base)
        if base is None:
            return None
        part = {8: t.BYTE, 16: t.WORD, 32: t.DWORD}[e.width]
        letter = {8: "B", 16: "W", 32: "D"}[e.width]
        if not isinstance(base, t.IntType):
            self.error(f"%{letter} access needs a bit string or integer, not {base.name}", e.span, "E035")
            return None
        count = base.bits // e.width
        if e.bit >= count:
            what = f"{base.name} has no {part.name}s" if count == 0 else f"{base.name} has {part.name}s 0..{count - 1}"
            self.error(f"%{letter}{e.bit} is outside {base.name}: {what}", e.span, "E035")
            return None
        return part

    def expr_Index(self, e: n.Index, expected) -> t.Type | None:
        base = self.bc.expr(e.base)
        for ix in e.indices:
            ity = self.bc.expr(ix)
            if ity is not None and not isinstance(ity, (t.IntType, t.EnumType)):
                self.error(f"array index must be an integer, not {ity.name}", ix.span, "E036")
        if base is None:
            return None
        if self.bc.stmts.byte_pointer(base) and len(e.indices) == 1 and t.byte_size(base.target) is not None:  # type: ignore[union-attr]
            return self.canonical(base.target)   # TwinCAT/CODESYS `p[i]`: the i-th element from p
        if not isinstance(base, t.ArrayType):
            self.error(f"'{self.describe(e.base)}' is {base.name}, not an array", e.span, "E036")
            return None
        if base.dims is None:
            if len(e.indices) != base.rank:
                self.error(f"an {base.name.split(' OF ')[0]} parameter takes {base.rank} index(es), got "
                           f"{len(e.indices)}", e.span, "E036")
            return base.element
        if len(e.indices) != len(base.dims):
            self.error(f"{base.name} needs {len(base.dims)} index(es), got {len(e.indices)}", e.span, "E036")
            return None
        for ix, (lo, hi) in zip(e.indices, base.dims):
            value = self.facts.consts.get(ix.nid)
            if isinstance(value, int) and not isinstance(value, bool) and not lo <= value <= hi:
                self.error(f"index {value} is outside the bounds {lo}..{hi}", ix.span, "E036")
        return base.element

    def expr_Deref(self, e: n.Deref, expected) -> t.Type | None:
        base = self.bc.expr(e.base)
        if base is None:
            return None
        if not isinstance(base, t.RefType) or base.flavour == "REFERENCE":
            self.error(f"'^' needs a reference (REF_TO or POINTER TO), but '{self.describe(e.base)}' is {base.name}",
                       e.span, "E037")
            return None
        if base.is_null:
            self.error("NULL cannot be dereferenced", e.span, "E037")
            return None
        return self.canonical(base.target)

    def canonical(self, ty: t.Type) -> t.Type:
        """A struct named inside its own declaration (`next : REF_TO Node`) was resolved to a
        placeholder without fields; the finished type replaces it."""
        if isinstance(ty, t.StructType):
            return self.c.structs.get(ty.qualname.lower(), ty)
        return ty

    def implicit_deref(self, e: n.Expr, ty: t.Type) -> t.Type:
        """A REFERENCE TO variable stands for its target wherever it is used (CODESYS)."""
        if isinstance(ty, t.RefType) and ty.flavour == "REFERENCE":
            self.facts.auto_deref.add(e.nid)
            return self.canonical(ty.target)
        return ty

    def expr_Unary(self, e: n.Unary, expected) -> t.Type | None:
        ty = self.bc.expr(e.operand, expected)
        if ty is None:
            return None
        if e.op == "NOT":
            if isinstance(ty, t.BoolType) or (isinstance(ty, t.IntType)):
                if e.operand.nid in self.facts.consts and isinstance(ty, t.BoolType):
                    self.facts.consts[e.nid] = not self.facts.consts[e.operand.nid]
                return ty
            self.error(f"NOT needs BOOL or a bit string, not {ty.name}", e.span, "E038")
            return None
        if isinstance(ty, (t.IntType, t.RealType)) or getattr(ty, "family", "") == "TIME":
            if e.operand.nid in self.facts.untyped:
                value = self.facts.consts[e.operand.nid]
                folded = -value if e.op == "MINUS" else value
                self.facts.untyped.add(e.nid)
                self.facts.consts[e.nid] = folded
                if isinstance(folded, int):
                    return int_literal_type(folded, self.settings)
                return ty
            if isinstance(ty, t.IntType) and not ty.signed and e.op == "MINUS":
                # IEC: negation of an unsigned value wraps; Sysmac accepts it
                return ty
            if e.operand.nid in self.facts.consts and e.op == "MINUS" and isinstance(self.facts.consts[e.operand.nid], (int, float)) \
                    and not isinstance(self.facts.consts[e.operand.nid], bool):
                self.facts.consts[e.nid] = -self.facts.consts[e.operand.nid]  # type: ignore[operator]
            return ty
        self.error(f"unary {OP_TEXT.get(e.op, e.op)} needs a number, not {ty.name}", e.span, "E038")
        return None

    def literal_fits(self, e: n.Expr, ty: t.Type) -> bool:
        value = self.facts.consts.get(e.nid)
        if isinstance(ty, t.IntType) and isinstance(value, int) and not isinstance(value, bool):
            return ty.lo <= value <= ty.hi
        if isinstance(ty, t.RealType):
            return isinstance(value, (int, float)) and not isinstance(value, bool)
        return False

    def expr_Binary(self, e: n.Binary, expected) -> t.Type | None:
        lt = self.bc.expr(e.left)
        rt = self.bc.expr(e.right)
        if lt is None or rt is None:
            return None
        lt, rt = dialect_rules.binary_operands(self.settings, lt, rt)   # non-strict enumerations as integers
        lu = e.left.nid in self.facts.untyped
        ru = e.right.nid in self.facts.untyped
        op = e.op
        sym = OP_TEXT.get(op, op)
        if op in LOGIC_OPS or op in ("EQ", "NE"):
            # IEC: 0 and 1 are BOOL literals (`b AND 1`, `b = 0`)
            if isinstance(lt, t.BoolType) and self.bool_literal(e.right):
                rt = t.BOOL
            elif isinstance(rt, t.BoolType) and self.bool_literal(e.left):
                lt = t.BOOL
        if op in COMPARE_OPS:
            if self.comparable(lt, rt, e.left, e.right, op):
                self.facts.types[e.nid] = t.BOOL
                operand = self.operand_type(lt, rt, lu, ru, e)
                if operand is not None:
                    self.facts.operand_types[e.nid] = operand
                return t.BOOL
            self.error(f"cannot compare {lt.name} {sym} {rt.name}", e.span, "E039")
            return None
        if op in LOGIC_OPS:
            if isinstance(lt, t.BoolType) and isinstance(rt, t.BoolType):
                return t.BOOL
            if op in ("AND_THEN", "OR_ELSE"):
                self.error(f"{sym} needs BOOL operands, not {lt.name} and {rt.name}", e.span, "E039")
                return None
            if isinstance(lt, t.IntType) and isinstance(rt, t.IntType):
                return self.operand_type(lt, rt, lu, ru, e)
            self.error(f"{sym} needs BOOL or bit-string operands, not {lt.name} and {rt.name}", e.span, "E039")
            return None
        # arithmetic
        if op == "POW":
            if isinstance(lt, (t.IntType, t.RealType)) and isinstance(rt, (t.IntType, t.RealType)):
                if isinstance(lt, t.RealType):
                    return t.LREAL if lu else lt
                return real_for(lt)  # type: ignore[arg-type]
            self.error(f"** needs numbers, not {lt.name} and {rt.name}", e.span, "E039")
            return None
        if lu and ru:
            folded = self.c.constants.const_value(e, self.pou_namespace, self.pou)
            if folded is not NOT_CONST and isinstance(folded, (int, float)):
                self.facts.untyped.add(e.nid)
                self.facts.consts[e.nid] = folded
                if isinstance(folded, int):
                    return int_literal_type(folded, self.settings)
                return t.LREAL
        if isinstance(lt, t.TimeType) or isinstance(rt, t.TimeType):
            return self.time_arith(e, lt, rt)
        if (op in ("PLUS", "MINUS") and self.bc.stmts.byte_pointer(lt) and isinstance(rt, t.IntType)
                or op == "PLUS" and isinstance(lt, t.IntType) and self.bc.stmts.byte_pointer(rt)) \
                and t.byte_size((lt if isinstance(lt, t.RefType) else rt).target) is not None:  # type: ignore[union-attr]
            # TwinCAT/CODESYS: `p + n` is the address n bytes further, of p's type
            self.facts.untyped.discard(e.nid)
            return lt if isinstance(lt, t.RefType) else rt
        if isinstance(lt, (t.IntType, t.RealType)) and isinstance(rt, (t.IntType, t.RealType)):
            if op == "MOD" and not (isinstance(lt, t.IntType) and isinstance(rt, t.IntType)):
                self.error(f"MOD needs integers, not {lt.name} and {rt.name}", e.span, "E039")
                return None
            return self.operand_type(lt, rt, lu, ru, e)
        self.error(f"operator {sym} cannot be applied to {lt.name} and {rt.name}", e.span, "E039")
        return None

    def bool_literal(self, e: n.Expr) -> bool:
        if e.nid in self.facts.untyped and self.facts.consts.get(e.nid) in (0, 1) \
                and not isinstance(self.facts.consts.get(e.nid), float):
            self.facts.types[e.nid] = t.BOOL
            self.facts.consts[e.nid] = bool(self.facts.consts[e.nid])
            return True
        return False

    def operand_type(self, lt: t.Type, rt: t.Type, lu: bool, ru: bool, e: n.Binary) -> t.Type | None:
        """The type a binary operation on these operands computes in."""
        if isinstance(lt, t.IntType) and isinstance(rt, t.IntType):
            if lu and not ru and self.literal_fits(e.left, rt):
                return rt
            if ru and not lu and self.literal_fits(e.right, lt):
                return lt
            return common_int(lt, rt)
        if isinstance(lt, t.RealType) and isinstance(rt, t.RealType):
            if lu and not ru:
                return rt
            if ru and not lu:
                return lt
            return t.LREAL if t.LREAL in (lt, rt) else t.REAL
        if isinstance(lt, t.RealType) and isinstance(rt, t.IntType):
            if lu:
                return t.REAL if ru or rt.bits <= 16 else real_for(rt)
            return lt if lt.bits == 64 or ru else (t.REAL if rt.bits <= 16 else t.LREAL)
        if isinstance(lt, t.IntType) and isinstance(rt, t.RealType):
            if ru:
                return t.REAL if lu or lt.bits <= 16 else real_for(lt)
            return rt if rt.bits == 64 or lu else (t.REAL if lt.bits <= 16 else t.LREAL)
        if lt == rt:
            return lt
        return None

    def comparable(self, lt: t.Type, rt: t.Type, le: n.Expr, re_: n.Expr, op: str) -> bool:
        if isinstance(lt, (t.IntType, t.RealType)) and isinstance(rt, (t.IntType, t.RealType)):
            return True
        if isinstance(lt, t.StringType) and isinstance(rt, t.StringType):
            return t.is_wide(lt) == t.is_wide(rt)
        if isinstance(lt, t.EnumType) and isinstance(rt, t.EnumType):
            return lt.qualname.lower() == rt.qualname.lower()
        if isinstance(lt, t.BoolType) and isinstance(rt, t.BoolType):
            return True
        if dialect_rules.enum_compares_with_integer(self.settings, lt, rt):
            return True   # TwinCAT/CODESYS: an enumeration compares with integers as its value
        if isinstance(lt, t.TimeType) and isinstance(rt, t.TimeType):
            return lt.family == rt.family
        if (isinstance(lt, t.InterfaceType) or isinstance(rt, t.InterfaceType)) and op in ("EQ", "NE"):
            others = [(ty, ex) for ty, ex in ((lt, le), (rt, re_)) if not isinstance(ty, t.InterfaceType)]
            return all(isinstance(ty, t.FBType) or (isinstance(ty, t.RefType) and ty.is_null) or self.bc.stmts.is_zero_literal(ex)
                       for ty, ex in others)
        if isinstance(lt, t.RefType) and isinstance(rt, t.RefType) and op in ("EQ", "NE"):
            return lt.is_null or rt.is_null or t.same_type(lt.target, rt.target) \
                or (self.bc.stmts.byte_pointer(lt) and self.bc.stmts.byte_pointer(rt))
        if op in ("EQ", "NE") and (self.bc.stmts.byte_pointer(lt) and self.bc.stmts.is_zero_literal(re_)
                                   or self.bc.stmts.byte_pointer(rt) and self.bc.stmts.is_zero_literal(le)):
            return True   # TwinCAT/CODESYS: `p = 0` tests for the NULL address
        return False

    def time_arith(self, e: n.Binary, lt: t.Type, rt: t.Type) -> t.Type | None:
        """IEC table 30 on the TIME family; a long operand (LTIME, LDT, …) makes the result long."""
        op = e.op
        ln, rn = getattr(lt, "family", lt.name), getattr(rt, "family", rt.name)
        long = getattr(lt, "long", False) or getattr(rt, "long", False)
        if op == "PLUS":
            if ln == rn == "TIME":
                return t.time_type("TIME", long)
            if ln in ("DATE_AND_TIME", "TIME_OF_DAY") and rn == "TIME":
                return t.time_type(ln, long)
            if rn in ("DATE_AND_TIME", "TIME_OF_DAY") and ln == "TIME":
                return t.time_type(rn, long)
        if op == "MINUS":
            if ln == rn:
                return t.time_type("TIME", long)
            if ln in ("DATE_AND_TIME", "TIME_OF_DAY") and rn == "TIME":
                return t.time_type(ln, long)
        if op in ("STAR", "SLASH") and ln == "TIME" and isinstance(rt, (t.IntType, t.RealType)):
            return lt
        if op == "STAR" and rn == "TIME" and isinstance(lt, (t.IntType, t.RealType)):
            return rt
        self.error(f"operator {OP_TEXT.get(op, op)} cannot be applied to {lt.name} and {rt.name}", e.span, "E039")
        return None

    def describe(self, e: n.Expr) -> str:
        if isinstance(e, n.Name):
            return e.text
        if isinstance(e, n.Member):
            return f"{self.describe(e.base)}.{e.name}"
        if isinstance(e, n.Index):
            return f"{self.describe(e.base)}[…]"
        if isinstance(e, n.Deref):
            return f"{self.describe(e.base)}^"
        if isinstance(e, n.Call):
            return f"{self.describe(e.callee)}(…)"
        return "expression"
