"""TwinCAT 3 and PLCopen XML sources: read as ST laid out on the XML's lines, so every
diagnostic, fault and trace names the XML file, line and column (stvm/syntax/vendor_xml.py)."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

from stvm.project import check, expand_paths, load
from stvm.syntax.vendor_xml import folder_sources, plcproj_items, read_vendor, translate
from tests.core_helpers import assert_no_traceback, cli

DATA = Path(__file__).parent / "data"
TWINCAT = DATA / "twincat"
TWINCAT_OO = DATA / "twincat_oo"
PLCOPEN = DATA / "plcopen" / "Conveyor.xml"


def _xml_position(xml: str, needle: str, nth: int = 0) -> tuple[int, int]:
    """1-based (line, column) of the nth occurrence of `needle` in the XML text."""
    offset = -1
    for _ in range(nth + 1):
        offset = xml.index(needle, offset + 1)
    line = xml.count("\n", 0, offset) + 1
    return line, offset - (xml.rfind("\n", 0, offset) + 1) + 1


def _st_position(st: str, needle: str, nth: int = 0) -> tuple[int, int]:
    return _xml_position(st, needle, nth)


# ---- TwinCAT: the ST text and its source map ------------------------------------------------------

def test_twincat_pou_text_keeps_every_character_at_its_xml_line_and_column():
    path = TWINCAT / "POUs" / "MAIN.TcPOU"
    st = read_vendor(path)
    xml = path.read_text(encoding="utf-8")
    assert st.original == xml
    assert st.source_map.identity
    assert len(st.splitlines()) <= len(xml.splitlines())
    for needle in ("PROGRAM MAIN", "fbCounter : FB_Counter;", "nCycles := nCycles + 1;", "END_IF",
                   "eState := E_State.eBusy;"):
        assert _st_position(st, needle) == _xml_position(xml, needle), needle
    # the glue stvm adds stands in the markup's columns, at the tag it replaces
    assert _st_position(st, "END_PROGRAM") == _xml_position(xml, "</POU>")
    assert "<" not in st and "CDATA" not in st


def test_twincat_methods_properties_and_actions_become_codesys_blocks_inside_the_fb():
    path = TWINCAT_OO / "FB_Axis.TcPOU"
    st = str(read_vendor(path))
    xml = path.read_text(encoding="utf-8")
    words = re.findall(r"\b(FUNCTION_BLOCK|END_FUNCTION_BLOCK|METHOD|END_METHOD|PROPERTY|END_PROPERTY|"
                       r"GET|END_GET|SET|END_SET)\b", st)
    assert words == ["FUNCTION_BLOCK", "METHOD", "END_METHOD", "PROPERTY", "GET", "END_GET", "SET", "END_SET",
                     "END_PROPERTY", "METHOD", "END_METHOD", "END_FUNCTION_BLOCK"]
    # the FB's own body comes first, then the method with its declaration and body
    assert st.index("_fPosition := _fPosition + _fVelocity;") < st.index("METHOD PUBLIC MoveTo : BOOL") \
        < st.index("MoveTo := TRUE;") < st.index("END_METHOD")
    # an action is a method without parameters, named as in the XML, at its Name attribute
    assert _st_position(st, "Halt") == _xml_position(xml, "Halt")
    assert st.index("Halt") < st.index("_fVelocity := 0.0;") < st.rindex("END_METHOD")
    for needle in ("METHOD PUBLIC MoveTo : BOOL", "PROPERTY Position : LREAL", "Position := _fPosition;",
                   "_fPosition := Position;", "_fVelocity := 0.0;"):
        assert _st_position(st, needle) == _xml_position(xml, needle), needle
    assert _st_position(st, "END_GET") == _xml_position(xml, "</Get>")
    assert _st_position(st, "END_FUNCTION_BLOCK") == _xml_position(xml, "</POU>")


def test_twincat_interface_file():
    st = str(read_vendor(TWINCAT_OO / "I_Axis.TcIO"))
    words = re.findall(r"\b(INTERFACE|END_INTERFACE|METHOD|END_METHOD|PROPERTY|END_PROPERTY|GET|END_GET)\b", st)
    assert words == ["INTERFACE", "METHOD", "END_METHOD", "PROPERTY", "GET", "END_GET", "END_PROPERTY",
                     "END_INTERFACE"]
    assert "fTarget : LREAL;" in st


def test_crlf_and_bom_files_keep_their_columns(tmp_path):
    xml = (TWINCAT / "POUs" / "FB_Counter.TcPOU").read_text(encoding="utf-8")
    bad = xml.replace("nCount := nCount + nStep;", "nCount := nCount + nStepp;")
    path = tmp_path / "FB_Counter.TcPOU"
    path.write_bytes(b"\xef\xbb\xbf" + bad.replace("\n", "\r\n").encode("utf-8"))
    _, diags, _ = check([path])
    errors = [d for d in diags if d.is_error]
    assert len(errors) == 1
    line, col = _xml_position(bad, "nStepp")
    assert (errors[0].span.file, errors[0].span.line, errors[0].span.column) == (str(path), line, col)


# ---- TwinCAT: whole projects ----------------------------------------------------------------------

def test_twincat_folder_runs_and_names_its_files():
    files, _, _ = expand_paths([TWINCAT])
    assert sorted(p.name for p in files) == ["E_State.TcDUT", "FB_Counter.TcPOU", "GVL_Main.TcGVL", "MAIN.TcPOU",
                                             "ST_Data.TcDUT"]
    project = load([TWINCAT], use_cache=False)
    vm = project.start()
    vm.run(cycles=3)
    assert vm["MAIN.nCycles"] == 3
    assert vm.format("MAIN.eState") == "E_State#eDone"
    assert vm["MAIN.stData.nValue"] == 6          # GVL_Main.nStep = 2, three calls
    assert project.sources[str(TWINCAT / "POUs" / "MAIN.TcPOU")].startswith("<?xml")


def test_plcproj_lists_the_sources():
    items = plcproj_items(TWINCAT / "Demo.plcproj")
    assert [p.name for p in items] == ["E_State.TcDUT", "ST_Data.TcDUT", "GVL_Main.TcGVL", "FB_Counter.TcPOU",
                                       "MAIN.TcPOU"]
    assert set(folder_sources(TWINCAT)) == set(items)
    rc, out, err = cli(["run", TWINCAT / "Demo.plcproj", "--cycles", "2", "--print", "MAIN.nCycles", "--no-cache"])
    assert (rc, out) == (0, "MAIN.nCycles = 2\n"), err


def test_cli_check_and_run_on_a_twincat_folder():
    rc, out, err = cli(["check", TWINCAT])
    assert rc == 0, err
    rc, out, err = cli(["run", TWINCAT, "--cycles", "3", "--print", "MAIN.stData", "--print", "nStep"])
    assert rc == 0, err
    assert out == "MAIN.stData = (nValue := 6, sName := 'counter')\nnStep = 2\n"


def _copy_twincat(tmp_path: Path) -> Path:
    target = tmp_path / "plc"
    shutil.copytree(TWINCAT, target)
    return target


def test_a_checker_error_names_the_xml_line_and_column(tmp_path):
    folder = _copy_twincat(tmp_path)
    main = folder / "POUs" / "MAIN.TcPOU"
    xml = main.read_text(encoding="utf-8").replace("stData.sName := 'counter';", "stData.sName := 42;")
    main.write_text(xml, encoding="utf-8")
    rc, _, err = cli(["check", folder])
    assert rc == 1
    assert_no_traceback(err)
    line, col = _xml_position(xml, "stData.sName := 42;")
    assert f"{main}:{line}:" in err and ": error:" in err
    # the excerpt is the XML file's own line
    assert "stData.sName := 42;" in err


def test_a_runtime_fault_names_the_xml_line(tmp_path):
    folder = _copy_twincat(tmp_path)
    main = folder / "POUs" / "MAIN.TcPOU"
    xml = main.read_text(encoding="utf-8").replace("nCycles := nCycles + 1;", "nCycles := nCycles + 1 + 0 * (10 / (nCycles - 2));")
    main.write_text(xml, encoding="utf-8")
    rc, _, err = cli(["run", folder, "--cycles", "5", "--no-cache"])
    assert rc == 3, err
    line, col = _xml_position(xml, "nCycles := nCycles + 1 + 0")
    assert f"{main}:{line}:" in err and "fault:" in err


def test_a_syntax_error_names_the_xml_line_and_column():
    xml = (TWINCAT / "POUs" / "FB_Counter.TcPOU").read_text(encoding="utf-8").replace(
        "nCount := nCount + nStep;", "nCount := nCount + nStep")
    st = translate(xml, "FB_Counter.TcPOU")
    from stvm.syntax.parser import parse_text
    _, diags = parse_text(st, "FB_Counter.TcPOU")
    assert diags and diags[0].is_error and "expected ';'" in diags[0].message
    # the missing ';' is reported at the token after it: the END_IF on the next line of the CDATA
    assert (diags[0].span.line, diags[0].span.column) == _xml_position(xml, "END_IF")


def test_a_body_in_another_language_is_an_error(tmp_path):
    xml = (TWINCAT / "POUs" / "FB_Counter.TcPOU").read_text(encoding="utf-8")
    start = xml.index("<ST>")
    end = xml.index("</ST>") + len("</ST>")
    xml = xml[:start] + "<SFC><step Name=\"Init\" /></SFC>" + xml[end:]
    path = tmp_path / "FB_Counter.TcPOU"
    path.write_text(xml, encoding="utf-8")
    rc, _, err = cli(["check", path])
    assert rc == 1
    assert_no_traceback(err)
    line, col = _xml_position(xml, "<Implementation>")
    assert f"{path}:{line}:{col}: error: POU 'FB_Counter' has a SFC body" in err


# ---- malformed and hostile XML ----------------------------------------------------------------------

@pytest.mark.parametrize("xml, needle, message", [
    ('<?xml version="1.0"?>\n<TcPlcObject>\n  <POU Name="X">\n  </PUO>\n</TcPlcObject>\n', "</PUO>",
     "malformed XML: mismatched tag"),
    ('<?xml version="1.0"?>\n<TcPlcObject>\n  <POU Name="X" Id=>\n</TcPlcObject>\n', "Id=>",
     "malformed XML: not well-formed"),
    ('<?xml version="1.0"?>\n<TcPlcObject>\n  <POU Name="X">\n', None, "malformed XML: no element found"),
])
def test_malformed_xml_is_a_located_error(tmp_path, xml, needle, message):
    path = tmp_path / "Broken.TcPOU"
    path.write_text(xml, encoding="utf-8")
    for command in ("check", "run"):
        rc, _, err = cli([command, path, "--no-cache"] if command == "run" else [command, path])
        assert rc == 1, err
        assert_no_traceback(err)
        assert f"{path}:" in err and f"error: {message}" in err
        if needle is not None:
            line, _ = _xml_position(xml, needle)
            assert f"{path}:{line}:" in err


def test_entity_declarations_are_refused(tmp_path):
    bomb = ('<?xml version="1.0"?>\n<!DOCTYPE lolz [\n <!ENTITY lol "lol">\n'
            ' <!ENTITY lol2 "&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;&lol;">\n]>\n'
            '<TcPlcObject><POU Name="X"><Declaration><![CDATA[&lol2;]]></Declaration></POU></TcPlcObject>\n')
    path = tmp_path / "Bomb.TcPOU"
    path.write_text(bomb, encoding="utf-8")
    rc, _, err = cli(["check", path])
    assert rc == 1
    assert_no_traceback(err)
    assert "entity declarations or external references is refused" in err


def test_external_entities_are_refused(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("PROGRAM Leak END_PROGRAM", encoding="utf-8")
    xxe = (f'<?xml version="1.0"?>\n<!DOCTYPE p [<!ENTITY x SYSTEM "file://{secret}">]>\n'
           '<TcPlcObject><POU Name="X"><Declaration>&x;</Declaration></POU></TcPlcObject>\n')
    path = tmp_path / "Xxe.TcPOU"
    path.write_text(xxe, encoding="utf-8")
    rc, _, err = cli(["check", path])
    assert rc == 1 and "refused" in err and "Leak" not in err


def test_a_wrong_root_element(tmp_path):
    path = tmp_path / "Other.TcPOU"
    path.write_text('<?xml version="1.0"?>\n<Project>\n</Project>\n', encoding="utf-8")
    rc, _, err = cli(["check", path])
    assert rc == 1
    assert f"{path}:2:1: error: not a TwinCAT source: the root element is <Project>" in err


# ---- PLCopen XML --------------------------------------------------------------------------------------

def test_plcopen_project_runs():
    rc, out, err = cli(["run", PLCOPEN, "--cycles", "3", "--print", "PLC_PRG.fbBelt.nTravel",
                        "--print", "PLC_PRG.aWeights", "--print", "PLC_PRG.stFirst", "--print", "PLC_PRG.fbBelt.eMode",
                        "--print", "PLC_PRG.nCount", "--print", "PLC_PRG.sMsg", "--no-cache"])
    assert rc == 0, err
    assert out.splitlines() == [
        "PLC_PRG.fbBelt.nTravel = 180",        # Clamp(60, 80) per scan
        "PLC_PRG.aWeights = [1.5, 2.5, 2.5]",  # arrayValue with repetitionValue
        "PLC_PRG.stFirst = (nId := 42, fWeight := 0.5, sLabel := 'box & lid')",
        "PLC_PRG.fbBelt.eMode = E_Mode#Running",
        "PLC_PRG.nCount = 9",                  # T_Count's initial value 7, +1 at 120 and 180
        "PLC_PRG.sMsg = 'travel > limit'",
    ]


def test_plcopen_task_interval_from_the_configuration():
    project = load([PLCOPEN], use_cache=False)
    tasks = project.model.tasks
    assert [(task.name, task.interval_ns) for task in tasks] == [("MainTask", 10_000_000)]


def test_plcopen_data_types_as_st():
    st = str(read_vendor(PLCOPEN))
    flat = " ".join(st.split())
    assert "E_Mode : ( Stopped := 0 , Running := 1 , Fault := 2 ) ;" in flat
    assert "ST_Item : STRUCT nId : UDINT ; fWeight : REAL := 0.5 ; sLabel : STRING [ 16 ] ; END_STRUCT ;" in flat
    assert "T_Slots : ARRAY [ 1 .. 5 ] OF ST_Item ;" in flat
    assert "T_Percent : INT ( 0 .. 100 ) ;" in flat
    assert "T_Count : UDINT := 7 ;" in flat
    assert "FUNCTION Clamp : INT VAR_INPUT nIn : INT ; nMax : INT ; END_VAR IF nIn > nMax THEN" in flat


def test_plcopen_names_stand_at_their_attributes():
    xml = PLCOPEN.read_text(encoding="utf-8")
    st = read_vendor(PLCOPEN)
    from stvm.syntax.parser import parse_text
    unit, diags = parse_text(st, str(PLCOPEN))
    assert not [d for d in diags if d.is_error]
    clamp = next(p for p in unit.pous if p.name == "Clamp")
    name, span = clamp.var_blocks[0].decls[1].names[0]
    assert name == "nMax" and (span.line, span.column) == _xml_position(xml, 'nMax"')
    types = {d.name: d for d in unit.types}
    assert (types["T_Slots"].span.line, types["T_Slots"].span.column) == _xml_position(xml, 'T_Slots"')


def test_plcopen_error_after_an_entity_keeps_its_column(tmp_path):
    xml = PLCOPEN.read_text(encoding="utf-8").replace("IF bRun AND nSpeed &lt;&gt; 0 THEN",
                                                      "IF bRun AND nSpeed &lt;&gt; 0 AND bMissing THEN")
    path = tmp_path / "Conveyor.xml"
    path.write_text(xml, encoding="utf-8")
    _, diags, sources = check([path])
    errors = [d for d in diags if d.is_error]
    assert len(errors) == 1 and "bMissing" in errors[0].message
    assert (errors[0].span.line, errors[0].span.column) == _xml_position(xml, "bMissing")
    assert sources[str(path)] == xml
    rc, _, err = cli(["check", path])
    line, col = _xml_position(xml, "bMissing")
    assert rc == 1 and f"{path}:{line}:{col}: error:" in err
    assert "&lt;&gt; 0 AND bMissing THEN" in err   # the excerpt is the XML line, caret under bMissing


def test_plcopen_gvl_name_qualifies_its_variables():
    st = str(read_vendor(PLCOPEN))
    assert "{attribute 'gvl' := 'GVL'} VAR_GLOBAL" in " ".join(st.split())


def test_plcopen_methods_in_codesys_add_data_at_text_level():
    xml = PLCOPEN.read_text(encoding="utf-8").replace(
        """        <addData />
      </pou>
      <pou name="PLC_PRG" pouType="program">""",
        """        <addData>
          <data name="http://www.3s-software.com/plcopenxml/method" handleUnknown="implementation">
            <Method name="Reset" ObjectId="9b1f2c3d-4e5f-4a6b-8c7d-0e1f2a3b4c5d">
              <interface>
                <returnType>
                  <BOOL />
                </returnType>
                <inputVars>
                  <variable name="nStart">
                    <type>
                      <DINT />
                    </type>
                  </variable>
                </inputVars>
              </interface>
              <body>
                <ST>
                  <xhtml xmlns="http://www.w3.org/1999/xhtml">nTravel := nStart;
Reset := nTravel &gt;= 0;</xhtml>
                </ST>
              </body>
              <addData />
            </Method>
          </data>
        </addData>
      </pou>
      <pou name="PLC_PRG" pouType="program">""")
    st = translate(xml, "Conveyor.xml")
    flat = " ".join(st.split())
    assert ("END_IF METHOD Reset : BOOL VAR_INPUT nStart : DINT ; END_VAR nTravel := nStart; "
            "Reset := nTravel >= 0; END_METHOD END_FUNCTION_BLOCK") in flat
    line, col = _xml_position(xml, "Reset := nTravel")
    assert st.source_map.position(*_st_position(st, "Reset := nTravel")) == (line, col)
    # after the entity `&gt;` the text stands 3 columns left of its place in the XML; the map puts it back
    st_line, st_col = _st_position(st, "Reset := nTravel >= 0;")
    zero = st_col + len("Reset := nTravel >= ")
    assert st.source_map.position(st_line, zero) == (line, col + len("Reset := nTravel &gt;= "))


def test_twincat_sources_are_read_in_the_twincat_dialect(tmp_path):
    xml = (TWINCAT / "POUs" / "FB_Counter.TcPOU").read_text(encoding="utf-8").replace("nCount", "_nCount")
    (tmp_path / "FB_Counter.TcPOU").write_text(xml, encoding="utf-8")
    main = ('<?xml version="1.0" encoding="utf-8"?>\n<TcPlcObject Version="1.1.0.1">\n'
            '  <POU Name="MAIN" Id="{00000000-0000-0000-0000-000000000001}" SpecialFunc="None">\n'
            '    <Declaration><![CDATA[PROGRAM MAIN\nVAR\n\tfb : FB_Counter;\n\ts : T_MaxString;\nEND_VAR\n]]>'
            '</Declaration>\n    <Implementation>\n      <ST><![CDATA[fb(bEnable := TRUE);\ns := \'ok\';]]></ST>\n'
            '    </Implementation>\n  </POU>\n</TcPlcObject>\n')
    (tmp_path / "MAIN.TcPOU").write_text(main, encoding="utf-8")
    # `_nCount` (a leading underscore, rejected by Sysmac) and T_MaxString (TwinCAT's) need no option
    rc, out, err = cli(["run", tmp_path, "--cycles", "2", "--print", "MAIN.fb._nCount", "--print", "MAIN.s",
                        "--no-cache"])
    assert (rc, out) == (0, "MAIN.fb._nCount = 2\nMAIN.s = 'ok'\n"), err
    rc, _, err = cli(["check", tmp_path, "--dialect", "sysmac"])
    assert rc == 1 and "name '_nCount' may not start with '_'" in err


def test_a_plcopen_name_that_is_not_an_identifier_is_an_error_at_its_attribute(tmp_path):
    xml = PLCOPEN.read_text(encoding="utf-8").replace('<variable name="nMax">', '<variable name="n Max;">')
    path = tmp_path / "Conveyor.xml"
    path.write_text(xml, encoding="utf-8")
    rc, _, err = cli(["check", path])
    assert rc == 1
    assert_no_traceback(err)
    line, col = _xml_position(xml, 'n Max;"')
    assert f"{path}:{line}:{col}: error: name='n Max;' of <variable> is not an ST identifier" in err


def test_the_debug_build_reads_vendor_files():
    from stvm.debug.build import load_debug
    build = load_debug([TWINCAT])
    main = str(TWINCAT / "POUs" / "MAIN.TcPOU")
    assert build.project.sources[main].startswith("<?xml")
    xml = (TWINCAT / "POUs" / "MAIN.TcPOU").read_text(encoding="utf-8")
    line, _ = _xml_position(xml, "stData.nValue := fbCounter.nCount;")
    found = build.pou_at(main, line)
    assert found is not None and found[1].name == "MAIN"


def test_lint_reads_vendor_files_and_reports_at_the_xml_position(tmp_path):
    xml = ('<?xml version="1.0" encoding="utf-8"?>\n<TcPlcObject Version="1.1.0.1">\n'
           '  <POU Name="F_Add" Id="{00000000-0000-0000-0000-000000000002}" SpecialFunc="None">\n'
           '    <Declaration><![CDATA[FUNCTION F_Add : INT\nVAR_INPUT\n\ta : INT;\nEND_VAR\nVAR\n\tt : INT;\n\t_nSpare : INT;\n'
           'END_VAR\n]]></Declaration>\n    <Implementation>\n      <ST><![CDATA[F_Add := t + a;]]></ST>\n'
           '    </Implementation>\n  </POU>\n</TcPlcObject>\n')
    path = tmp_path / "F_Add.TcPOU"
    path.write_text(xml, encoding="utf-8")
    rc, out, err = cli(["lint", path])
    line, col = _xml_position(xml, "t + a")
    # `_nSpare` (a leading underscore) is fine: TwinCAT files are linted in the twincat dialect
    assert rc == 1 and f"{path}:{line}:{col}: warning[SA101]: 't' is read before it is written" in out + err
    assert "error" not in err
    broken = tmp_path / "Broken.TcPOU"
    broken.write_text("<TcPlcObject>\n<POU>\n</TcPlcObject>\n", encoding="utf-8")
    rc, out, err = cli(["lint", broken])
    assert rc != 0
    assert_no_traceback(out + err)
    assert f"{broken}:3:" in out + err and "malformed XML" in out + err


def test_mutated_vendor_files_never_raise_anything_but_a_source_error():
    """Deterministic mutation fuzz: cut, insert and replace markup in the fixtures; reading them is
    ST text or a located SourceError, and the ST text parses to diagnostics, never an exception."""
    import random

    from stvm.source import SourceError
    from stvm.syntax.parser import parse_text

    files = sorted(DATA.rglob("*.Tc*")) + [PLCOPEN]
    texts = [(p.name, p.read_text(encoding="utf-8")) for p in files]
    pieces = ["<", ">", "&", "&lt;", "]]>", "<![CDATA[", '"', "'", "\n", "{", "}", "</ST>", "<ST>", "&#10;",
              "(*", "//", "<a/>", 'name="x"', "<variable/>", "<dimension/>", "<baseType/>"]
    rnd = random.Random(11)
    outcomes = {"st": 0, "error": 0}
    for _ in range(400):
        name, text = rnd.choice(texts)
        chars = list(text)
        for _ in range(rnd.randint(1, 4)):
            k = rnd.randrange(len(chars))
            op = rnd.random()
            if op < 0.4:
                del chars[k:k + rnd.randint(1, 30)]
            elif op < 0.8:
                chars.insert(k, rnd.choice(pieces))
            else:
                chars[k] = rnd.choice("<>&\"' x\n;")
        try:
            st = translate("".join(chars), name)
        except SourceError as exc:
            assert exc.line >= 1 and exc.column >= 1 and exc.message
            outcomes["error"] += 1
            continue
        parse_text(st, name)
        outcomes["st"] += 1
    assert outcomes["st"] > 50 and outcomes["error"] > 50, outcomes


def test_content_runs_keep_offsets_through_crlf_entities_and_cdata():
    from stvm.syntax.vendor_xml import _content
    xml = "<ST>a &lt;= b;\r\n<!-- note --><![CDATA[x\r\ny]]>&#65;\rz</ST>"
    runs = _content(xml, 4, xml.index("</ST>"))
    assert "".join(piece for piece, _ in runs) == "a <= b;\nx\nyA\nz"
    for piece, offset in runs:
        if piece == "\n":
            assert xml[offset] in "\r\n"
        elif len(piece) == 1 and xml[offset] == "&":
            continue                      # an entity: one character at its '&'
        else:
            assert xml[offset:offset + len(piece)] == piece


def test_a_breakpoint_on_an_xml_line_stops_there(tmp_path):
    main = TWINCAT / "POUs" / "MAIN.TcPOU"
    xml = main.read_text(encoding="utf-8")
    line, _ = _xml_position(xml, "stData.nValue := fbCounter.nCount;")
    commands = tmp_path / "cmds"
    commands.write_text(f"break {main}:{line}\ncontinue\nprint fbCounter.nCount\nquit\n", encoding="utf-8")
    rc, out, err = cli(["debug", TWINCAT, "-x", commands])
    assert_no_traceback(out + err)
    assert f"Breakpoint 1: {main}:{line} in MAIN" in out
    assert f"   {line}  stData.nValue := fbCounter.nCount;" in out   # the listing is the XML file's line
    assert "fbCounter.nCount = 2" in out


def test_plcopen_codesys_attributes_are_honoured(tmp_path):
    attrs = ('<addData>\n          <data name="http://www.3s-software.com/plcopenxml/attributes" '
             'handleUnknown="implementation">\n            <Attributes>\n'
             '              <Attribute Name="qualified_only" Value="" />\n'
             '              <Attribute Name="strict" Value="" />\n            </Attributes>\n          </data>\n'
             '        </addData>\n')
    xml = PLCOPEN.read_text(encoding="utf-8")
    # E_Mode and the GVL become qualified_only, as CODESYS exports them
    xml = xml.replace('''          </enum>
        </baseType>
      </dataType>''', '''          </enum>
        </baseType>
        ''' + attrs + '''      </dataType>''', 1)
    xml = xml.replace('''      <globalVars name="GVL">''', '''      <globalVars name="GVL">
        ''' + attrs.replace("        ", "    "), 1)
    path = tmp_path / "Conveyor.xml"
    path.write_text(xml, encoding="utf-8")
    rc, _, err = cli(["check", path])
    assert rc == 0, err        # the project writes E_Mode.Running and GVL.bStart
    bad = xml.replace("eMode := E_Mode.Running;", "eMode := Running;").replace("GVL.bStart", "bStart")
    path.write_text(bad, encoding="utf-8")
    rc, _, err = cli(["check", path])
    assert rc == 1
    assert "'Running' is an enumerator of E_Mode, which is {attribute 'qualified_only'}" in err
    assert "'bStart' is in the global variable list GVL, which is {attribute 'qualified_only'}" in err
    line, col = _xml_position(bad, "bStart, nSpeed")
    assert f"{path}:{line}:{col}: error: 'bStart'" in err
