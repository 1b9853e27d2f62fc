"""The checked project: what the checker hands the code generator and the runtime.

Plain, picklable data (the load cache stores it): POU signatures with resolved variable types,
globals, configuration/tasks. The per-expression facts the code generator needs (types, what each
name resolves to) live in `Analysis.facts`, keyed by node identity, and are not cached.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from stvm.semantics.types import Type
from stvm.source import NO_SPAN, Span   # start-up: not the syntax tree (a cached load unpickles this)

INPUT, OUTPUT, IN_OUT, LOCAL, TEMP, GLOBAL, EXTERNAL = (
    "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR", "VAR_TEMP", "VAR_GLOBAL", "VAR_EXTERNAL")


@dataclass(frozen=True)
class SiblingInstance:
    """The initial value (or FB_init argument) `itf : I_X := fbOther;` / `fb : F(fbOther)` in a
    FUNCTION_BLOCK or PROGRAM: the instance `name` declared before it in the same POU (CODESYS /
    TwinCAT: the instance's address is a constant of the load). The lowering writes the sibling's
    storage."""

    name: str


@dataclass(frozen=True)
class AddressInit:
    """The initial value `r : REF_TO INT := REF(counter);` (or ADR() for a POINTER TO; the
    `ref_initial_value` row): a reference bound when the instance (`scope` "self": a PROGRAM's or
    FUNCTION_BLOCK's variable) or the globals (`scope` "global") are made. `steps` lead from there
    to the variable: ("field", declared name) for a variable or member, ("item", 0-based offset)
    for an array element; `aggregate`: the target is a STRUCT, ARRAY or FB instance, whose
    reference is the object itself (semantics/dialect_rules.py builds it, lower/gen_pou.py writes
    it)."""

    scope: str
    steps: tuple[tuple[str, object], ...]
    aggregate: bool


@dataclass
class Variable:
    """One declared variable: its section, type, initial value and attributes."""

    name: str                 # the user's spelling
    section: str              # VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR, VAR_TEMP, VAR_GLOBAL, VAR_EXTERNAL
    type: Type
    constant: bool = False
    span: Span = NO_SPAN
    init: object = None       # the constant initial value (runtime representation) or None for the type default
    # CODESYS `fb : F(1, nMax := 5)`: F's FB_init inputs given in the declaration, {input key: value}
    fb_args: dict | None = None
    # TwinCAT `{attribute 'instance-path'}` on a STRING member of an FB: the VM writes the path of
    # each instance into it at start (stdlib/tc2_system.py `fill_instance_paths`)
    instance_path: bool = False

    @property
    def key(self) -> str:
        return self.name.lower()


@dataclass
class POUInfo:
    """One PROGRAM, FUNCTION_BLOCK, FUNCTION or METHOD: its kind, result and variables."""

    name: str
    qualname: str             # namespace path joined with '\'
    kind: str                 # FUNCTION, FUNCTION_BLOCK, PROGRAM
    return_type: Type | None
    variables: dict[str, Variable] = field(default_factory=dict)  # key → Variable, in declaration order
    native: bool = False
    generic: bool = False
    variadic: bool = False
    typed: bool = False       # native wants the static argument types (`{native typed}`)
    aliases: dict[str, str] = field(default_factory=dict)         # pin alias key → pin key
    # native: the key of the input pin whose value `impl.quiet` names (`{native quiet:Execute}`,
    # stdlib/registry.py): a call with that pin at that value is skipped
    quiet_pin: str | None = None
    file: str = ""
    span: Span = NO_SPAN
    # object orientation (IEC ed. 3 6.6.5-6.6.6): a METHOD is a POUInfo of kind METHOD whose
    # `owner` is its FB's (or interface's) key; an INTERFACE is a POUInfo of kind INTERFACE
    methods: dict[str, "POUInfo"] = field(default_factory=dict)         # own methods, key → METHOD
    properties: dict[str, "PropertyInfo"] = field(default_factory=dict)  # own properties
    base: str | None = None           # FB EXTENDS: the base FB's key
    interfaces: tuple[str, ...] = ()  # IMPLEMENTS (FB) / EXTENDS (INTERFACE): keys as declared
    owner: str = ""                   # METHOD: the key of the FB or interface declaring it
    access: str = "PUBLIC"            # METHOD/PROPERTY: PUBLIC, PRIVATE, PROTECTED, INTERNAL
    abstract: bool = False
    final: bool = False
    inherited: int = 0                # FB: how many of `variables` (the first ones) come from the base
    inst_vars: dict[str, str] = field(default_factory=dict)  # METHOD: VAR_INST key → the instance variable's key
    stat_vars: dict[str, str] = field(default_factory=dict)  # VAR_STAT key → its hidden global's key
    call_after_init: bool = False     # METHOD with {attribute 'call_after_init'} (CODESYS): run after FB_init

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


@dataclass
class PropertyInfo:
    """PROPERTY P : T of an FB or interface: GET is a METHOD returning T (named P), SET a METHOD
    with the input P."""

    name: str
    type: Type
    getter: POUInfo | None
    setter: POUInfo | None
    owner: str = ""
    access: str = "PUBLIC"
    span: Span = NO_SPAN

    @property
    def key(self) -> str:
        return self.name.lower()


@dataclass
class TaskInfo:
    """One task of the configuration: period, priority and the program instances it runs."""

    name: str
    interval_ns: int
    priority: int
    programs: list[tuple[str, str]]   # (instance name, program qualname)


@dataclass
class ProjectModel:
    """What the checker hands the lowering: POUs, globals, tasks and the declared types."""

    pous: dict[str, POUInfo]              # qualname key → POU
    globals: dict[str, Variable]          # key → global variable
    tasks: list[TaskInfo]                 # empty: a default task for the lone programs
    default_programs: list[str]           # program qualnames to run in the default task
    structs: dict[str, Type]              # qualname key → StructType
    enums: dict[str, Type]                # qualname key → EnumType
