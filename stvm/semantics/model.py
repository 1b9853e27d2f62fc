"""The checked project: what the checker hands the code generator and the runtime.

Plain, picklable data (the load cache stores it): POU signatures with resolved variable types,
globals, configuration/tasks. The per-expression facts the code generator needs (types, what each
name resolves to) live in `Analysis.facts`, keyed by node identity, and are not cached.
"""

from __future__ import annotations


from stvm.records import FACTORY, FrozenRecord, Record
from stvm.semantics.types import Type
from stvm.source import NO_SPAN, Span   # start-up: not the syntax tree (a cached load unpickles this)

INPUT, OUTPUT, IN_OUT, LOCAL, TEMP, GLOBAL, EXTERNAL = (
    "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR", "VAR_TEMP", "VAR_GLOBAL", "VAR_EXTERNAL")

# The classes below behave as the dataclasses they were (`__init__` parameters and defaults, `==`
# over every field, `repr`, frozenness, unhashable when mutable, the `__dict__` pickle stores)
# but are `stvm.records` classes (`__init__` written out, the rest derived from `_FIELDS`): `dataclass`
# builds each class's methods with `exec` at import, a cost of
# every `stvm run` (issue 33 item 5; tests/semantics/test_model_records.py compares them).
_set = object.__setattr__


class SiblingInstance(FrozenRecord):
    """The initial value (or FB_init argument) `itf : I_X := fbOther;` / `fb : F(fbOther)` in a
    FUNCTION_BLOCK or PROGRAM: the instance `name` declared before it in the same POU (CODESYS /
    TwinCAT: the instance's address is a constant of the load). The lowering writes the sibling's
    storage."""

    _FIELDS = ('name',)

    def __init__(self, name: str) -> None:
        _set(self, "name", name)


class AddressInit(FrozenRecord):
    """The initial value `r : REF_TO INT := REF(counter);` (or ADR() for a POINTER TO; the
    `ref_initial_value` row): a reference bound when the instance (`scope` "self": a PROGRAM's or
    FUNCTION_BLOCK's variable) or the globals (`scope` "global") are made. `steps` lead from there
    to the variable: ("field", declared name) for a variable or member, ("item", 0-based offset)
    for an array element; `aggregate`: the target is a STRUCT, ARRAY or FB instance, whose
    reference is the object itself (semantics/dialect_rules.py builds it, lower/gen_pou.py writes
    it)."""

    _FIELDS = ('scope', 'steps', 'aggregate')

    def __init__(self, scope: str, steps: tuple[tuple[str, object], ...], aggregate: bool) -> None:
        _set(self, "scope", scope)
        _set(self, "steps", steps)
        _set(self, "aggregate", aggregate)


class Variable(Record):
    """One declared variable: its section, type, initial value and attributes.

    `name`: the user's spelling; `section`: VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR, VAR_TEMP,
    VAR_GLOBAL, VAR_EXTERNAL; `init`: the constant initial value (runtime representation) or None
    for the type default; `fb_args`: CODESYS `fb : F(1, nMax := 5)`, F's FB_init inputs given in
    the declaration, {input key: value}; `instance_path`: TwinCAT `{attribute 'instance-path'}`
    on a STRING member of an FB, into which the VM writes the path of each instance at start
    (stdlib/tc2_system.py `fill_instance_paths`)."""

    _FIELDS = ('name', 'section', 'type', 'constant', 'span', 'init', 'fb_args', 'instance_path')

    def __init__(self, name: str, section: str, type: Type, constant: bool = False, span: Span = NO_SPAN,
                 init: object = None, fb_args: dict | None = None, instance_path: bool = False) -> None:
        self.name = name
        self.section = section
        self.type = type
        self.constant = constant
        self.span = span
        self.init = init
        self.fb_args = fb_args
        self.instance_path = instance_path

    @property
    def key(self) -> str:
        return self.name.lower()


class POUInfo(Record):
    """One PROGRAM, FUNCTION_BLOCK, FUNCTION or METHOD: its kind, result and variables.

    `qualname`: the namespace path joined with '\\'; `kind`: FUNCTION, FUNCTION_BLOCK, PROGRAM,
    METHOD or INTERFACE; `variables`: key → Variable, in declaration order; `typed`: a native
    that wants the static argument types (`{native typed}`); `aliases`: pin alias key → pin key;
    `quiet_pin`: for a native, the key of the input pin whose value `impl.quiet` names (`{native
    quiet:Execute}`, stdlib/registry.py): a call with that pin at that value is skipped.
    Object orientation (IEC ed. 3 6.6.5-6.6.6): a METHOD is a POUInfo of kind METHOD whose
    `owner` is its FB's (or interface's) key, an INTERFACE one of kind INTERFACE; `methods`: own
    methods, key → METHOD; `properties`: own properties; `base`: FB EXTENDS, the base FB's key;
    `interfaces`: IMPLEMENTS (FB) / EXTENDS (INTERFACE), keys as declared; `access` (METHOD,
    PROPERTY): PUBLIC, PRIVATE, PROTECTED, INTERNAL; `inherited`: for an FB, how many of
    `variables` (the first ones) come from the base; `inst_vars`: METHOD, VAR_INST key → the
    instance variable's key; `stat_vars`: VAR_STAT key → its hidden global's key;
    `call_after_init`: a METHOD with {attribute 'call_after_init'} (CODESYS), run after FB_init."""

    _FIELDS = ('name', 'qualname', 'kind', 'return_type', 'variables', 'native', 'generic', 'variadic', 'typed', 'aliases', 'quiet_pin', 'file', 'span', 'methods', 'properties', 'base', 'interfaces', 'owner', 'access', 'abstract', 'final', 'inherited', 'inst_vars', 'stat_vars', 'call_after_init')

    def __init__(self, name: str, qualname: str, kind: str, return_type: Type | None,
                 variables: dict[str, Variable] = FACTORY, native: bool = False, generic: bool = False,
                 variadic: bool = False, typed: bool = False, aliases: dict[str, str] = FACTORY,
                 quiet_pin: str | None = None, file: str = "", span: Span = NO_SPAN,
                 methods: dict[str, POUInfo] = FACTORY, properties: dict[str, PropertyInfo] = FACTORY,
                 base: str | None = None, interfaces: tuple[str, ...] = (), owner: str = "",
                 access: str = "PUBLIC", abstract: bool = False, final: bool = False, inherited: int = 0,
                 inst_vars: dict[str, str] = FACTORY, stat_vars: dict[str, str] = FACTORY,
                 call_after_init: bool = False) -> None:
        self.name = name
        self.qualname = qualname
        self.kind = kind
        self.return_type = return_type
        self.variables = {} if variables is FACTORY else variables
        self.native = native
        self.generic = generic
        self.variadic = variadic
        self.typed = typed
        self.aliases = {} if aliases is FACTORY else aliases
        self.quiet_pin = quiet_pin
        self.file = file
        self.span = span
        self.methods = {} if methods is FACTORY else methods
        self.properties = {} if properties is FACTORY else properties
        self.base = base
        self.interfaces = interfaces
        self.owner = owner
        self.access = access
        self.abstract = abstract
        self.final = final
        self.inherited = inherited
        self.inst_vars = {} if inst_vars is FACTORY else inst_vars
        self.stat_vars = {} if stat_vars is FACTORY else stat_vars
        self.call_after_init = call_after_init

    @property
    def key(self) -> str:
        return self.qualname.lower()

    def params(self) -> list[Variable]:
        """Inputs then in-outs, in declaration order: the positional parameter order."""
        inputs = [v for v in self.variables.values() if v.section == INPUT]
        in_outs = [v for v in self.variables.values() if v.section == IN_OUT]
        return inputs + in_outs

    def pin(self, name: str) -> Variable | None:
        key = name.lower()
        key = self.aliases.get(key, key)
        return self.variables.get(key)


class PropertyInfo(Record):
    """PROPERTY P : T of an FB or interface: GET is a METHOD returning T (named P), SET a METHOD
    with the input P."""

    _FIELDS = ('name', 'type', 'getter', 'setter', 'owner', 'access', 'span')

    def __init__(self, name: str, type: Type, getter: POUInfo | None, setter: POUInfo | None,
                 owner: str = "", access: str = "PUBLIC", span: Span = NO_SPAN) -> None:
        self.name = name
        self.type = type
        self.getter = getter
        self.setter = setter
        self.owner = owner
        self.access = access
        self.span = span

    @property
    def key(self) -> str:
        return self.name.lower()


class TaskInfo(Record):
    """One task of the configuration: period, priority and the program instances it runs,
    (instance name, program qualname)."""

    _FIELDS = ('name', 'interval_ns', 'priority', 'programs')

    def __init__(self, name: str, interval_ns: int, priority: int, programs: list[tuple[str, str]]) -> None:
        self.name = name
        self.interval_ns = interval_ns
        self.priority = priority
        self.programs = programs


class ProjectModel(Record):
    """What the checker hands the lowering: POUs (qualname key → POU), globals (key → global
    variable), tasks (empty: a default task for the lone programs), the program qualnames to run
    in the default task, and the declared types (qualname key → StructType / EnumType)."""

    _FIELDS = ('pous', 'globals', 'tasks', 'default_programs', 'structs', 'enums')

    def __init__(self, pous: dict[str, POUInfo], globals: dict[str, Variable], tasks: list[TaskInfo],
                 default_programs: list[str], structs: dict[str, Type], enums: dict[str, Type]) -> None:
        self.pous = pous
        self.globals = globals
        self.tasks = tasks
        self.default_programs = default_programs
        self.structs = structs
        self.enums = enums

