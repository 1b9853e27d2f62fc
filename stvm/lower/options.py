"""The lowering's optimisations, each a named switch.

Every optimisation keeps the ST semantics exactly (tests/lower/test_lower_options_differential.py
runs the core and thesis suites with all of them off, and with each alone off, and compares); they
only change how fast the generated code runs. Whether one applies is decided by a named function of
the analysis pass (stvm/lower/analysis.py: `cached_vars`, `range_for_ok`, `hoistable_accesses`,
`inlinable_fb`, `direct_native_call`, `reused_array_ref`, `held_deref`, frameless METHODs in `plan_body`); the
ones that only change how an expression is written are read by their generator (`ring_chain`,
`no_wrap_in_range` in gen_expr.py, `inline_struct_assign` in gen_pou.py, `inline_input_copy` in
gen_stmt.py). The
debug build switches `cache_locals` off, because a debugger stopped inside a call must read and
write the storage the code itself uses (see `stvm/debug/build.py`).
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace


@dataclass(frozen=True)
class LowerOptions:
    # A call keeps its POU's often-used variables in Python locals and writes the scalars back in
    # a `finally` (LOAD_FAST instead of attribute access).
    cache_locals: bool = True
    # A METHOD none of whose variables is passed by reference runs without a frame object: its
    # variables are Python locals. Needs `cache_locals`.
    frameless_methods: bool = True
    # FOR with a constant step, the end evaluated once and an unassigned local loop variable
    # becomes a Python `for … in range()`. Needs `cache_locals`.
    range_for: bool = True
    # Inside a range-FOR, `a[i + c]` gets one bounds check before the loop instead of one per
    # access (a checked copy of the loop runs when the check fails). Needs `range_for`.
    hoist_bounds: bool = True
    # `i + k` on a range-FOR variable that provably stays in its type needs no wrap code.
    # Needs `range_for`.
    no_wrap_in_range: bool = True
    # A chain of + - * in one integer type wraps once at its end (arithmetic modulo 2^n).
    ring_chain: bool = True
    # Which variables a call caches is decided by the uses one call is expected to make (a use in
    # one of the n ways of an IF or CASE counts 1/n, a use in a loop ten times; FOR variables
    # always qualify, a range-FOR needs them) instead of all uses in the body: a CASE step
    # machine's FB, idle on most calls, no longer loads and stores back every step's variables
    # on every call. Safe: only chooses among the variables `cache_locals` may cache. Needs
    # `cache_locals`.
    hot_path_cache: bool = True
    # A STRUCT assignment copies nested STRUCT fields inline (one Python call per assignment).
    inline_struct_assign: bool = True
    # A STRUCT input or output of an FB call (`fb(Socket := x)`, `fb(Socket => x)`) is copied
    # field by field at the call site instead of through the struct's `_assign` (one Python call
    # less per input and call). Safe: the same stores in the same order; a struct of more than 32
    # leaf fields keeps the call.
    inline_input_copy: bool = True
    # In a run of plain native FB call statements (`fb(Socket := CBT.Socket, ...)` three to six
    # times in a row in every thesis FB), the first field-by-field copy from a struct keeps its
    # leaf values in Python locals and the next copies from the same struct store those. Safe: a
    # natively implemented FB touches only its own instance, and the run admits only calls whose
    # in-outs are arrays (no struct field reachable), whose inputs are plain variable paths and
    # whose outputs are plain scalar variables; any other statement, and any copy into the
    # source's own instance, ends it. Needs `inline_input_copy` and `cache_locals` (the debug build
    # switches the latter off: a debugger stopped between two calls may change the source).
    share_struct_sources: bool = True
    # A native FB's call site calls its implementation (`fb._impl.call(fb, _ctx)`) instead of the
    # generated `__call__` that only forwards to it: one Python frame less per call (the thesis
    # makes ~30 socket and timer FB calls a scan). Safe: the same call, and the instance is of
    # exactly that class (the checker lets no POU EXTEND a native FB).
    direct_native_calls: bool = True
    # A native FB whose declaration names a quiet pin (`{native quiet:Execute}`: the socket FBs)
    # is called only when that pin is not `impl.quiet`, the value for which its implementation
    # says the call would change nothing (the thesis makes ~28 socket FB calls a scan, nearly all
    # idle). Safe: a skipped call is one that would have stored nothing. Needs
    # `direct_native_calls`.
    skip_quiet_native_calls: bool = True
    # A fixed array passed to an FB's ARRAY[*] parameter (`SendDat := Data[0]`) reuses the
    # `ArrayRef` the instance holds from the previous call when it names the same list and element
    # (no object built per call). Safe: an `ArrayRef` is immutable and a fixed array's list is never
    # replaced, so the kept one is indistinguishable from a new one.
    reuse_array_refs: bool = True
    # The body of a tiny BOOL FB (R_TRIG, F_TRIG, SR, RS: at most four assignments among its own
    # BOOL variables) is written into the caller, on the instance, instead of called (the thesis
    # calls ten edge detectors a scan). Safe: the same stores in the same order on the same
    # instance; not for FBs with methods, a base, temporaries or in-outs, nor FBs some POU extends.
    # The debug build switches it off (breakpoints in the FB's body must hit).
    inline_small_fbs: bool = True
    # A loop whose only storage is Python locals and one reference's scalar target (`r^ := r^ + i`
    # with nothing else that could alias it: no calls, no member, index or other dereference)
    # reads `r^` into a local before the loop and writes it back in a `finally` after it (a NULL
    # `r` runs the loop as written, so the dereference faults at its line). Needs `cache_locals`
    # (`r` and the other variables must be Python locals).
    hold_derefs_in_loops: bool = True

    @classmethod
    def none(cls) -> "LowerOptions":
        """Every optimisation off: the reference lowering of the differential test."""
        return cls(**{f.name: False for f in fields(cls)})

    def without(self, *names: str) -> "LowerOptions":
        """These options with the named optimisations switched off."""
        unknown = [name for name in names if name not in self.names()]
        if unknown:
            raise ValueError(f"unknown lowering optimisation {unknown[0]!r}; known: {', '.join(self.names())}")
        return replace(self, **{name: False for name in names})

    @classmethod
    def names(cls) -> tuple[str, ...]:
        return tuple(f.name for f in fields(cls))


DEFAULT_OPTIONS = LowerOptions()
