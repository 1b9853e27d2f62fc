"""stvm/semantics/instance_inits.py, pass 3 of the checker (once every POU is declared):
`fb : F := (x := 1)` and `fb : F(1, 2)` resolved against F's variables and FB_init."""

from __future__ import annotations

from checker_passes import checker, messages

from stvm.settings import Dialect

SOURCE = """
PROGRAM Main
VAR
  a : Drive := (speed := 5, name := 'x');
  b : Drive(3, bFast := TRUE);
END_VAR
END_PROGRAM
FUNCTION_BLOCK Drive
VAR_INPUT speed : INT; END_VAR
VAR name : STRING[4]; END_VAR
VAR_IN_OUT io : INT; END_VAR
METHOD FB_init : BOOL
VAR_INPUT bInitRetains : BOOL; bInCopyCode : BOOL; nAxis : INT; bFast : BOOL; END_VAR
END_METHOD
END_FUNCTION_BLOCK
"""


def declared_only(source: str):
    ck = checker(source, dialect=Dialect.TWINCAT)
    ck.indexer.build_index()
    ck.declarations.declare_all()
    ck.oo.link_oo()
    return ck


def test_the_queues_wait_for_every_pou_then_resolve_in_declaration_order():
    ck = declared_only(SOURCE)
    main = ck.ctx.pous["main"]
    # Drive is declared after Main: its variables were not known when Main's were declared
    assert main.variables["a"].init == {} and len(ck.ctx.fb_instance_inits) == 1
    assert main.variables["b"].fb_args is None and len(ck.ctx.fb_init_arg_decls) == 1
    ck.instance_inits.resolve_fb_instance_inits()
    ck.instance_inits.resolve_fb_init_args()
    assert main.variables["a"].init == {"speed": 5, "name": b"x"}
    assert main.variables["b"].fb_args == {"naxis": 3, "bfast": True}
    assert ck.ctx.fb_instance_inits == [] and ck.ctx.fb_init_arg_decls == [] and messages(ck) == []


def test_what_an_initialiser_may_not_set_is_reported():
    ck = declared_only(SOURCE.replace("(speed := 5, name := 'x')", "(io := 1, nope := 2, speed := 1, speed := 2)")
                       .replace("Drive(3, bFast := TRUE)", "Drive(1, TRUE, 3)"))
    ck.instance_inits.resolve_fb_instance_inits()
    ck.instance_inits.resolve_fb_init_args()
    assert messages(ck) == [
        ("E024", "'io' of Drive is an in-out (a reference, bound at each call): an instance initialiser cannot set it"),
        ("E024", "function block Drive has no variable 'nope' to initialise"),
        ("E024", "'speed' is initialised twice"),
        ("E063", "too many FB_init arguments: Drive's FB_init takes 2 besides bInitRetains and bInCopyCode"),
    ]
