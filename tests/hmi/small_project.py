"""A small ST project with one page that uses every widget kind (API and page-format tests)."""

from __future__ import annotations

from pathlib import Path

SOURCE = """
TYPE Mode : (Idle, Run, Stop); END_TYPE
TYPE Pt : STRUCT X : REAL; Y : REAL; Z : REAL; END_STRUCT; END_TYPE
VAR_GLOBAL
    Start : BOOL; Hold : BOOL; Lamp : BOOL; Speed : UINT; Gain : REAL; Name : STRING[11];
    M : Mode; Pose : UINT; Count : DINT; Edges : DINT; Msg : STRING[20]; Target : Pt; Secret : INT;
END_VAR
PROGRAM Main
VAR_EXTERNAL
    Start : BOOL; Hold : BOOL; Lamp : BOOL; Count : DINT; Edges : DINT; Msg : STRING[20];
    Name : STRING[11];
END_VAR
VAR Trig : R_TRIG; END_VAR
Lamp := Start;
Count := Count + 1;
Trig(CLK := Hold);
IF Trig.Q THEN Edges := Edges + 1; END_IF;
Msg := Name;
END_PROGRAM
"""

MANIFEST = """
[project]
files = ["main.st"]
dialect = "sysmac"   # a thesis-style project: Omron's STRING[n] (n - 1 bytes of text) and conversions

[hmi]
pages = ["hmi/Test.toml", "hmi/Main.toml"]
start = "Main"
"""

MAIN_PAGE = """
[page]
name = "Main"
title = "Main"

[[area]]
title = "Go"
[[area.widget]]
kind = "nav"
page = "Test"
label = "Test page"
"""

TEST_PAGE = """
[page]
name = "Test"
title = "Every widget"

[[area]]
title = "Inputs"

[[area.widget]]
kind = "lamp"
var = "Lamp"
label = "Running"

[[area.widget]]
kind = "numeric"
var = "Speed"
label = "Speed"
min = 10
max = 100
unit = "%"

[[area.widget]]
kind = "numeric"
var = "Gain"
label = "Gain"

[[area.widget]]
kind = "dropdown"
var = "M"
label = "Mode"

[[area.widget]]
kind = "dropdown"
var = "Pose"
label = "Pose"
options = { RIGHTY = 0, LEFTY = 1 }

[[area.widget]]
kind = "text"
var = "Name"
label = "Name"

[[area.widget]]
kind = "status"
var = "Msg"
label = "Message"

[[area.widget]]
kind = "status"
var = "Count"
label = "Scans"

[[area.widget]]
kind = "toggle"
var = "Start"
label = "Start"

[[area.widget]]
kind = "momentary"
var = "Hold"
label = "Jog"

[[area.widget]]
kind = "set"
var = "Speed"
value = 50
label = "Half speed"

[[area.widget]]
kind = "preset"
preset = "Defaults"

[[area.widget]]
kind = "preset"
preset = "Pulse"

[[area.widget]]
kind = "nav"
page = "Main"
label = "Main Menu"

[[area.widget]]
kind = "popup"
popup = "Axis"
instance = "X"
label = "Edit X"

[[area.widget]]
kind = "note"
label = "a note"

[[area]]
title = "Robot"
[[area.widget]]
kind = "robot_view"
targets = ["Target"]
history_s = 5

[[popup]]
name = "Axis"
title = "Axis {n}"
instances = ["X", "Y"]
[[popup.widget]]
kind = "numeric"
var = "Target.{n}"
label = "{n}"
min = -500
max = 500

[[preset]]
name = "Defaults"
label = "Defaults"
[preset.values]
Speed = 20
Gain = 1.5
Name = "hello"
M = "Run"

[[preset]]
name = "Pulse"
label = "Pulse"
[[preset.step]]
Hold = false
[[preset.step]]
Hold = true
"""


def write_project(folder: Path, test_page: str = TEST_PAGE) -> Path:
    (folder / "hmi").mkdir(parents=True, exist_ok=True)
    (folder / "main.st").write_text(SOURCE)
    (folder / "stvm.toml").write_text(MANIFEST)
    (folder / "hmi" / "Main.toml").write_text(MAIN_PAGE)
    (folder / "hmi" / "Test.toml").write_text(test_page)
    return folder / "main.st"
