"""What the parts of the body checks share (docs/architecture.md, "Checker passes").

One `body.BodyChecker` checks one POU or METHOD body; it makes one of each part (statements.py,
expressions.py, members.py, calls.py, intrinsics.py). A part reads the fixed facts of the body
(`c`: the Checker, `pou`, `node`, `fb`, `fb_node`, `facts`, `settings`, `pou_namespace`) from its
own attributes and reaches everything else through `bc`, the BodyChecker: the state of the walk
(`loop_depth`, `for_vars`, `member_base`, `en_call`, `rejected_calls`), the dispatch (`expr`,
`statement`), the hooks the debugger overrides (`resolve_name`, `member_visible`, `lvalue`:
stvm/debug/scope.py) and the other parts (`bc.calls.bind_args(…)`).
"""

from __future__ import annotations

from stvm.syntax import nodes as n


class BodyPart:
    """One part of a body check."""

    def __init__(self, bc) -> None:
        # the BodyChecker holds its parts and each part it: a cycle, which `BodyChecker.release`
        # breaks once the body is checked (else it would keep the Checker and the syntax tree alive
        # until the collector runs: tests/test_load_garbage.py). Not a weak proxy: the parts call
        # through `bc` at every node, and a proxy cost ~10 % of a check.
        self.bc = bc
        self.c = bc.c
        self.pou = bc.pou
        self.node = bc.node
        self.fb = bc.fb
        self.fb_node = bc.fb_node
        self.facts = bc.facts
        self.settings = bc.settings
        self.pou_namespace = bc.fb_node.namespace

    def error(self, message: str, span: n.Span, code: str = "") -> None:
        self.c.error(message, span, code)
