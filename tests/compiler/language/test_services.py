"""The language services as an engineer meets them in the editor: hover, go to definition,
find references, rename, completion and the outline, on the demo project, on a project of
two files (a function block in one, the program that uses it in another) and on text
that does not parse while it is being typed."""

from __future__ import annotations

from dataclasses import replace

from backend.compiler.language.analysis import Analysis, analyse
from backend.compiler.language.completion import complete
from backend.compiler.language.hover import hover
from backend.compiler.language.language_project import LanguageProject
from backend.compiler.language.navigation import definition, references
from backend.compiler.language.outline import outline
from backend.compiler.language.position import Location, Range
from backend.compiler.language.rename import apply, rename
from backend.engineering.project import demo_project_path

TANK = (demo_project_path() / "tank.st").read_text(encoding="utf-8")

MOTOR = """\
(* a motor with a soft start *)
FUNCTION_BLOCK Motor
VAR_INPUT
  run : BOOL;      (* the motor should turn *)
  ramp : TIME := T#2s;
END_VAR
VAR_OUTPUT
  speed : REAL;
END_VAR
VAR
  x : INT;
END_VAR
METHOD PUBLIC Reset : BOOL
VAR_INPUT
  hard : BOOL;
END_VAR
speed := 0.0;
Reset := hard;
END_METHOD
x := x + 1;
IF run THEN speed := speed + 1.0; END_IF;
END_FUNCTION_BLOCK
"""

MAIN = """\
PROGRAM Main
VAR
  pump : Motor;
  x : INT;
  t1 : TON;
END_VAR
pump(run := x > 3);
x := x + 1;
pump.Reset(hard := TRUE);
t1(IN := pump.speed > 10.0, PT := T#5s);
END_PROGRAM
"""


def at(text: str, needle: str, nth: int = 1, offset: int = 0) -> tuple[int, int]:
    """Line and column (1-based) of the nth occurrence of `needle` in `text`, plus `offset`."""
    index = -1
    for _ in range(nth):
        index = text.index(needle, index + 1)
    line = text.count("\n", 0, index) + 1
    col = index - (text.rfind("\n", 0, index) + 1) + 1
    return line, col + offset


def two_files() -> Analysis:
    return analyse({"motor.st": MOTOR, "main.st": MAIN})


def text_at(analysis: Analysis, location: Location) -> str:
    line = analysis.texts[location.file].splitlines()[location.range.line - 1]
    return line[location.range.col - 1 : location.range.end_col - 1]


# ---- hover ----------------------------------------------------------------------------------


def test_hover_on_a_local_shows_its_declaration_initial_value_and_comment() -> None:
    analysis = analyse({"tank.st": TANK})
    line, col = at(TANK, "level >= highLevel")
    shown = hover(analysis, "tank.st", line, col + 2)
    assert shown is not None
    assert shown.signature == "VAR level : INT := 500"
    assert shown.comment == "the tank level: the plant's last good measurement"
    assert shown.owner == "TankControl"
    assert shown.range == Range(line, col, line, col + len("level"))
    assert "Declared in TankControl (tank.st:8)" in shown.markdown


def test_hover_on_a_global_shows_its_address_and_on_an_instance_member_the_standard_fb() -> None:
    analysis = analyse({"tank.st": TANK})
    shown = hover(analysis, "tank.st", *at(TANK, "tankLevel < 0"))
    assert shown is not None
    assert shown.signature == "VAR_GLOBAL tankLevel AT %IW0 : INT := -1"
    assert "-1 until it answers" in shown.comment
    member = hover(analysis, "tank.st", *at(TANK, "refillDelay.Q", offset=12))
    assert member is not None
    assert member.signature == "VAR_OUTPUT Q : BOOL"
    assert member.owner == "TON"


def test_hover_on_a_pou_shows_its_interface_and_on_a_standard_function_its_parameters() -> None:
    analysis = two_files()
    shown = hover(analysis, "main.st", *at(MAIN, "Motor"))
    assert shown is not None
    assert shown.signature.splitlines() == [
        "FUNCTION_BLOCK Motor",
        "  VAR_INPUT run : BOOL",
        "  VAR_INPUT ramp : TIME",
        "  VAR_OUTPUT speed : REAL",
    ]
    assert shown.comment == "a motor with a soft start"
    method = hover(analysis, "main.st", *at(MAIN, "Reset"))
    assert method is not None
    assert method.signature.splitlines() == ["METHOD Motor.Reset : BOOL", "  VAR_INPUT hard : BOOL"]
    text = "PROGRAM P\nVAR y : INT; END_VAR\ny := LIMIT(0, y, 10);\nEND_PROGRAM\n"
    standard = hover(analyse({"p.st": text}), "p.st", *at(text, "LIMIT"))
    assert standard is not None
    assert standard.signature == "LIMIT(MN, IN, MX) (standard function)"
    assert standard.declared is None


def test_hover_on_an_elementary_type_shows_its_range() -> None:
    analysis = analyse({"tank.st": TANK})
    shown = hover(analysis, "tank.st", *at(TANK, "INT := 500"))
    assert shown is not None and shown.signature == "INT: 16-bit signed integer, -32768..32767"
    assert shown.declared is None
    assert not rename(analysis, "tank.st", *at(TANK, "INT := 500"), "Int16").ok


def test_no_hover_on_a_keyword_a_literal_or_a_comment() -> None:
    analysis = analyse({"tank.st": TANK})
    assert hover(analysis, "tank.st", *at(TANK, "END_IF")) is None
    assert hover(analysis, "tank.st", *at(TANK, "T#2s", offset=2)) is None
    assert hover(analysis, "tank.st", *at(TANK, "the pump should run")) is None
    assert hover(analysis, "other.st", 1, 1) is None


# ---- definition and references --------------------------------------------------------------


def test_definition_of_a_global_used_in_the_program_is_its_var_global_line() -> None:
    analysis = analyse({"tank.st": TANK})
    found = definition(analysis, "tank.st", *at(TANK, "level := tankLevel", offset=9))
    line, col = at(TANK, "tankLevel AT")
    assert found == Location("tank.st", Range(line, col, line, col + len("tankLevel")))


def test_definition_crosses_files_from_the_program_to_the_function_block() -> None:
    analysis = two_files()
    found = definition(analysis, "main.st", *at(MAIN, "pump.speed", offset=5))
    assert found is not None and found.file == "motor.st"
    assert text_at(analysis, found) == "speed"
    assert found.range.line == at(MOTOR, "speed : REAL")[0]
    to_block = definition(analysis, "main.st", *at(MAIN, "Motor"))
    assert (
        to_block is not None and to_block.range.line == 2 and text_at(analysis, to_block) == "Motor"
    )
    # a standard function block has no file in the project to go to
    assert definition(analysis, "main.st", *at(MAIN, "TON")) is None


def test_references_of_an_input_are_its_declaration_its_uses_and_the_named_arguments() -> None:
    analysis = two_files()
    found = references(analysis, "motor.st", *at(MOTOR, "run : BOOL"))
    assert [(place.file, place.range.line) for place in found] == [
        ("main.st", at(MAIN, "run :=")[0]),
        ("motor.st", at(MOTOR, "run : BOOL")[0]),
        ("motor.st", at(MOTOR, "IF run")[0]),
    ]
    assert all(text_at(analysis, place) == "run" for place in found)
    without = references(
        analysis, "motor.st", *at(MOTOR, "IF run", offset=3), include_declaration=False
    )
    assert len(without) == 2


def test_a_local_of_the_same_name_in_two_pous_is_two_symbols() -> None:
    analysis = two_files()
    in_main = references(analysis, "main.st", *at(MAIN, "x := x + 1"))
    in_motor = references(analysis, "motor.st", *at(MOTOR, "x := x + 1"))
    assert {place.file for place in in_main} == {"main.st"}
    assert {place.file for place in in_motor} == {"motor.st"}
    assert len(in_main) == 4  # declared, `x > 3`, written and read
    assert len(in_motor) == 3


def test_references_of_a_method_find_the_call_through_the_instance() -> None:
    analysis = two_files()
    found = references(analysis, "motor.st", *at(MOTOR, "Reset : BOOL"))
    assert [(place.file, text_at(analysis, place)) for place in found] == [
        ("main.st", "Reset"),
        ("motor.st", "Reset"),
        ("motor.st", "Reset"),  # its result, assigned in its body
    ]


# ---- rename ---------------------------------------------------------------------------------


def test_rename_a_local_edits_every_use_and_the_result_compiles() -> None:
    analysis = analyse({"tank.st": TANK})
    result = rename(analysis, "tank.st", *at(TANK, "level :"), "heldLevel")
    assert result.ok, result.refusal
    assert [edits.file for edits in result.files] == ["tank.st"]
    renamed = apply(TANK, result.files[0].edits)
    assert renamed.count("heldLevel") == 5
    assert "tankLevel" in renamed  # the global of a similar name is left alone
    assert not [d for d in analyse({"tank.st": renamed}).diagnostics if d.severity == "error"]


def test_rename_an_input_across_files_renames_the_named_arguments() -> None:
    analysis = two_files()
    result = rename(analysis, "main.st", *at(MAIN, "run :="), "enable")
    assert result.ok, result.refusal
    texts = {edits.file: apply(analysis.texts[edits.file], edits.edits) for edits in result.files}
    assert "pump(enable := x > 3);" in texts["main.st"]
    assert "enable : BOOL;" in texts["motor.st"] and "IF enable THEN" in texts["motor.st"]


def test_rename_refuses_with_a_reason() -> None:
    analysis = two_files()
    speed = at(MOTOR, "speed : REAL")
    refusals = {
        name: rename(analysis, "motor.st", *speed, name).refusal
        for name in ("run", "2fast", "END_IF", "INT", "LIMIT", "a__b")
    }
    assert refusals["run"].startswith("'run' already names a variable in Motor")
    assert "not an identifier" in refusals["2fast"]
    assert "keyword" in refusals["END_IF"]
    assert "elementary type" in refusals["INT"]
    assert "standard function" in refusals["LIMIT"]
    assert "not an identifier" in refusals["a__b"]
    standard = rename(analysis, "main.st", *at(MAIN, "TON"), "Timer")
    assert "standard library" in standard.refusal
    program = rename(analysis, "main.st", *at(MAIN, "Main"), "Plant")
    assert "PROGRAM, which padt.toml's program instances name" in program.refusal
    nothing = rename(analysis, "main.st", *at(MAIN, "END_VAR"), "y")
    assert not nothing.ok and not nothing.files


def test_rename_to_a_name_taken_where_the_symbol_is_named_is_refused() -> None:
    # free in Motor, but `x` is Main's own variable, and Main names the block
    analysis = two_files()
    result = rename(analysis, "motor.st", *at(MOTOR, "Motor"), "x")
    assert not result.ok
    assert result.refusal.startswith("'x' already names a variable in Main")
    # a method's parameter may not take the name of its block's variable
    hidden = rename(analysis, "motor.st", *at(MOTOR, "hard :"), "speed")
    assert hidden.refusal.startswith("'speed' already names a variable in Motor.Reset")


# ---- completion -----------------------------------------------------------------------------


def labels(analysis: Analysis, file: str, line: int, col: int) -> list[str]:
    return [item.label for item in complete(analysis, file, line, col)]


def test_completion_after_an_instance_offers_its_inputs_outputs_and_methods() -> None:
    analysis = two_files()
    line, col = at(MAIN, "pump.Reset", offset=5)
    assert labels(analysis, "main.st", line, col) == ["ramp", "Reset", "run", "speed"]
    reset = next(i for i in complete(analysis, "main.st", line, col) if i.label == "Reset")
    assert (reset.kind, reset.insert_text, reset.snippet) == ("method", "Reset(hard := ${1})", True)
    line, col = at(TANK, "refillDelay.Q", offset=12)
    assert labels(analyse({"tank.st": TANK}), "tank.st", line, col) == ["ET", "IN", "PT", "Q"]


def test_completion_of_a_prefix_offers_locals_first_then_globals() -> None:
    analysis = analyse({"tank.st": TANK})
    line, col = at(TANK, "pumpStarts := pumpStarts + 1", offset=4)
    found = complete(analysis, "tank.st", line, col)
    assert [i.label for i in found] == ["pump", "pumpStarts", "pumpCommand", "pumpRunning"]
    assert found[0].detail == "VAR : BOOL" and found[0].documentation == "the pump should run"


def test_completion_offers_standard_fbs_and_instance_calls_as_snippets() -> None:
    analysis = two_files()
    line = at(MAIN, "END_PROGRAM")[0]
    found = complete(analysis, "main.st", line, 1)
    items = {(item.label, item.kind): item for item in found}
    assert items["TON", "function_block"].insert_text == "TON(IN := ${1}, PT := ${2})"
    assert items["t1(...)", "snippet"].insert_text == "t1(IN := ${1}, PT := ${2})"
    assert items["LIMIT", "function"].insert_text == "LIMIT(${1:MN}, ${2:IN}, ${3:MX})"
    assert items["IF", "snippet"].insert_text.startswith("IF ${1:condition} THEN")
    assert items["FUNCTION_BLOCK", "snippet"].insert_text.startswith("FUNCTION_BLOCK ${1:Name}")
    assert items["TYPE STRUCT", "snippet"].snippet
    assert items["Motor", "function_block"].insert_text == "Motor(run := ${1}, ramp := ${2})"
    assert ("ELSIF", "keyword") in items
    # the program's own variables come first, the keywords last
    assert [item.label for item in found[:4]] == ["pump", "pump(...)", "t1", "t1(...)"]
    assert found[-1].kind == "keyword"


def test_completion_in_a_call_offers_the_parameters_first_in_their_order() -> None:
    analysis = analyse({"tank.st": TANK})
    line, col = at(TANK, "refillDelay(IN", offset=12)
    found = complete(analysis, "tank.st", line, col)
    assert [(i.label, i.insert_text) for i in found[:4]] == [
        ("IN :=", "IN := "),
        ("PT :=", "PT := "),
        ("Q =>", "Q => "),
        ("ET =>", "ET => "),
    ]
    assert found[4].label == "alarmLow"  # then what may be passed
    line, col = at(MAIN, "pump.Reset(hard", offset=11)
    assert labels(two_files(), "main.st", line, col)[0] == "hard :="


def test_completion_after_a_colon_in_a_var_block_offers_types() -> None:
    types = "TYPE Color : (Red, Green); END_TYPE\n"
    text = "PROGRAM P\nVAR\n  c : \nEND_VAR\nEND_PROGRAM\n"
    analysis = LanguageProject({"types.st": types, "p.st": text}).analysis()
    found = labels(analysis, "p.st", 3, 7)
    assert {"BOOL", "INT", "TON", "Color", "ARRAY"} <= set(found)
    assert "IF" not in found


def test_completion_while_the_line_being_typed_does_not_parse() -> None:
    project = LanguageProject({"tank.st": TANK})
    line = at(TANK, "alarmLow := level")[0]
    lines = TANK.splitlines()
    lines.insert(line - 1, "IF refillDelay.")
    project.set_text("tank.st", "\n".join(lines) + "\n")
    analysis = project.analysis()
    assert any(d.severity == "error" and d.file == "tank.st" for d in analysis.diagnostics)
    assert labels(analysis, "tank.st", line, len("IF refillDelay.") + 1) == ["ET", "IN", "PT", "Q"]
    lines[line - 1] = "IF pum"
    project.set_text("tank.st", "\n".join(lines) + "\n")
    found = labels(project.analysis(), "tank.st", line, len("IF pum") + 1)
    assert found[:2] == ["pump", "pumpStarts"]


def test_completion_knows_a_variable_declared_in_text_that_does_not_parse() -> None:
    text = "PROGRAM P\nVAR\n  motorA : Motor;\n  count : INT\nEND_VAR\nmotorA.\nEND_PROGRAM\n"
    project = LanguageProject({"motor.st": MOTOR, "p.st": text})
    analysis = project.analysis()
    assert "P" not in analysis.user_pous  # the program does not parse
    assert labels(analysis, "p.st", 6, 8) == ["ramp", "Reset", "run", "speed"]
    assert "count" in labels(analysis, "p.st", 6, 1)


def test_definition_and_hover_follow_the_text_typed_since_the_last_analysis() -> None:
    # while a line is half typed the services read names from the last analysis that
    # resolved (as backend/engineering/language_service does), over the text as it is
    good = analyse({"tank.st": TANK})
    lines = TANK.splitlines()
    at_body = at(TANK, "alarmPlant := tankLevel")[0]
    lines[7:7] = ["  spare1 : INT;", "  spare2 : INT;"]  # two declarations above `level`
    lines.insert(at_body + 1, "IF level >")  # and a line that does not parse
    typed = "\n".join(lines) + "\n"
    analysis = replace(good, texts={"tank.st": typed})
    line, col = at(typed, "level >= highLevel")
    found = definition(analysis, "tank.st", line, col)
    assert found is not None and found.range.line == at(typed, "level : INT")[0]
    shown = hover(analysis, "tank.st", line, col)
    assert shown is not None and shown.signature == "VAR level : INT := 500"
    assert shown.comment == "the tank level: the plant's last good measurement"


def test_no_completion_inside_a_comment_or_a_string() -> None:
    analysis = analyse({"tank.st": TANK})
    assert complete(analysis, "tank.st", *at(TANK, "the pump should run", offset=4)) == []


# ---- outline --------------------------------------------------------------------------------


def test_outline_of_the_demo_lists_the_program_its_variables_and_the_global_list() -> None:
    analysis = analyse({"tank.st": TANK})
    symbols = outline(analysis, "tank.st")
    assert [(s.kind, s.name) for s in symbols] == [
        ("program", "TankControl"),
        ("global_list", "VAR_GLOBAL"),
    ]
    program, globals_ = symbols
    assert [c.name for c in program.children][:3] == ["level", "pump", "highLevel"]
    assert program.children[0].detail == "VAR : INT"
    assert program.range.line == at(TANK, "PROGRAM")[0]
    assert program.range.end_line == at(TANK, "END_PROGRAM")[0]
    assert program.selection_range == Range(*at(TANK, "TankControl"), 6, 20)
    assert [c.name for c in globals_.children] == ["tankLevel", "pumpRunning", "pumpCommand"]


def test_outline_nests_methods_and_struct_members() -> None:
    text = "TYPE Point : STRUCT x : REAL; y : REAL; END_STRUCT; END_TYPE\n" + MOTOR
    symbols = outline(analyse({"m.st": text}), "m.st")
    point, motor = symbols
    assert (point.kind, [c.name for c in point.children]) == ("struct", ["x", "y"])
    assert [(c.kind, c.name) for c in motor.children] == [
        ("variable", "run"),
        ("variable", "ramp"),
        ("variable", "speed"),
        ("variable", "x"),
        ("method", "Reset"),
    ]
    assert [c.name for c in motor.children[-1].children] == ["hard"]


# ---- object orientation, qualified names ----------------------------------------------------

OOP = """\
TYPE Color : (Red, Green, Blue); END_TYPE
INTERFACE IRunnable
METHOD Run : BOOL
VAR_INPUT fast : BOOL; END_VAR
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Base IMPLEMENTS IRunnable
VAR level : INT; END_VAR
METHOD PUBLIC Run : BOOL
VAR_INPUT fast : BOOL; END_VAR
THIS^.level := 1;
Run := fast;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Derived EXTENDS Base
VAR shade : Color := Color.Green; END_VAR
SUPER^.Run(fast := FALSE);
level := level + 1;
END_FUNCTION_BLOCK
PROGRAM Main
VAR d : Derived; r : IRunnable; ok : BOOL; END_VAR
d();
r := d;
ok := r.Run(fast := TRUE);
ok := d.Run(fast := FALSE);
END_PROGRAM
"""


def test_names_through_this_super_an_interface_and_an_inherited_variable() -> None:
    analysis = analyse({"oop.st": OOP})
    assert not [d for d in analysis.diagnostics if d.severity == "error"]
    level = at(OOP, "level : INT")
    found = references(analysis, "oop.st", *level)
    lines = [place.range.line for place in found]
    # declared in Base, written through THIS^ in Base's method, used in Derived (inherited)
    assert lines == [
        level[0],
        at(OOP, "THIS^")[0],
        at(OOP, "level := level")[0],
        at(OOP, "level := level")[0],
    ]
    run_through_interface = definition(analysis, "oop.st", *at(OOP, "r.Run", offset=2))
    assert run_through_interface is not None and run_through_interface.range.line == 3
    run_of_base = definition(analysis, "oop.st", *at(OOP, "SUPER^.Run", offset=7))
    assert run_of_base is not None and run_of_base.range.line == at(OOP, "METHOD PUBLIC Run")[0]
    green = definition(analysis, "oop.st", *at(OOP, "Color.Green", offset=6))
    assert green is not None and (green.range.line, text_at(analysis, green)) == (1, "Green")
    members = labels(analysis, "oop.st", *at(OOP, "d.Run", offset=2))
    assert "Run" in members and "level" not in members  # Base's own VAR stays inside
    this = labels(analysis, "oop.st", *at(OOP, "THIS^.level", offset=6))
    assert this == ["level", "Run"]  # inside the block its own variables too


# ---- hostile requests -------------------------------------------------------------------------


def test_requests_anywhere_and_with_any_name_get_an_answer_not_a_traceback() -> None:
    broken = "PROGRAM P\nVAR x : INT; END_VAR\n(* never closed\nx := 'never closed\n" + "a." * 5000
    deep = "PROGRAM Q\nVAR y : INT; END_VAR\ny := " + "(" * 5000 + "\nEND_PROGRAM\n"
    analysis = analyse({"tank.st": TANK, "broken.st": broken, "deep.st": deep})
    places = [(0, 0), (-5, -5), (1, 10**9), (10**9, 1), (3, 3), (5, 9999), (3, 10**6)]
    for file in ("tank.st", "broken.st", "deep.st", "absent.st", "../tank.st"):
        for line, col in places:
            assert hover(analysis, file, line, col) is None or file == "tank.st"
            definition(analysis, file, line, col)
            references(analysis, file, line, col)
            complete(analysis, file, line, col)
            assert not rename(analysis, file, line, col, "y").files or file == "tank.st"
        outline(analysis, file)
    chain_end = broken.count("\n") + 1, len("a." * 5000) + 1
    assert complete(analysis, "broken.st", *chain_end) == []  # all in the unclosed comment
    in_string = "PROGRAM S\nVAR s : STRING; END_VAR\ns := 'TO\nEND_PROGRAM\n"
    assert complete(analyse({"s.st": in_string}), "s.st", 3, 9) == []
    level = at(TANK, "level :")
    for name in ("x" * 1_000_000, "a\x00b", "", " level", "lével"):
        refused = rename(analysis, "tank.st", *level, name)
        assert not refused.ok and len(refused.refusal) < 300
