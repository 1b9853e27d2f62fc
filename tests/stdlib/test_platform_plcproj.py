"""A TwinCAT `.plcproj` names its sources in XML attributes: `POUs\\Time&amp;Date\\X.TcPOU` is the
folder `Time&Date` (the OSCAT port for TwinCAT has one), so a library loaded from it gets them."""

from __future__ import annotations

from stvm.syntax.vendor_xml import plcproj_items

POU = """<?xml version="1.0" encoding="utf-8"?>
<TcPlcObject Version="1.1.0.1">
  <POU Name="DAY_OF_WEEK" Id="{00000000-0000-0000-0000-000000000001}">
    <Declaration><![CDATA[FUNCTION DAY_OF_WEEK : INT
VAR_INPUT
    IDATE : DATE;
END_VAR]]></Declaration>
    <Implementation><ST><![CDATA[DAY_OF_WEEK := 1;]]></ST></Implementation>
  </POU>
</TcPlcObject>
"""


def test_an_escaped_ampersand_in_a_compile_item(tmp_path) -> None:
    folder = tmp_path / "POUs" / "Time&Date"
    folder.mkdir(parents=True)
    (folder / "DAY_OF_WEEK.TcPOU").write_text(POU, encoding="utf-8")
    proj = tmp_path / "lib.plcproj"
    proj.write_text('<Project><ItemGroup><Compile Include="POUs\\Time&amp;Date\\DAY_OF_WEEK.TcPOU">'
                    '<SubType>Code</SubType></Compile></ItemGroup></Project>', encoding="utf-8")
    assert plcproj_items(proj) == [folder / "DAY_OF_WEEK.TcPOU"]
