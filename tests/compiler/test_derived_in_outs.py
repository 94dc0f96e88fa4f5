"""What the compiler takes and refuses around instances of derived blocks and references
in declarations (docs/language.md, "Object orientation" and "References"): a derived
instance is an in-out of its base type; nothing may replace it by a smaller base instance
(E0314) or store a base where the caller holds a derived (E0401); a reference starts as
NULL or as REF(x) of its own instance (E0117 for a POU's REF of a global). What these
programs do on both tiers is in tests/runtime/native/test_native_oop.py and
tests/runtime/native/test_native_declarations.py."""

from __future__ import annotations

from tests.compiler.test_references import diagnostics

BLOCKS = """
INTERFACE ISpeaker
METHOD Speak : INT
END_METHOD
END_INTERFACE
FUNCTION_BLOCK Animal IMPLEMENTS ISpeaker
VAR_INPUT sound : INT; END_VAR
METHOD PUBLIC Speak : INT
Speak := sound;
END_METHOD
END_FUNCTION_BLOCK
FUNCTION_BLOCK Dog EXTENDS Animal
VAR barks : INT; END_VAR
END_FUNCTION_BLOCK
FUNCTION_BLOCK Cat
END_FUNCTION_BLOCK
"""


def errors(source: str) -> list[str]:
    return [d for d in diagnostics(BLOCKS + source) if "error" in d]


def test_a_derived_instance_is_an_in_out_of_its_base_type_and_nothing_else_is() -> None:
    source = """
FUNCTION Hear : INT
VAR_IN_OUT a : Animal; END_VAR
Hear := a.Speak();
END_FUNCTION
FUNCTION_BLOCK Vet
VAR_IN_OUT patient : Animal; END_VAR
patient.sound := patient.sound + 1;
END_FUNCTION_BLOCK
PROGRAM Main
VAR d : Dog; a : Animal; c : Cat; v : Vet; y : INT; END_VAR
y := Hear(d) + Hear(a);
v(patient := d);
y := Hear(c);
v(patient := c);
END_PROGRAM
"""
    assert errors(source) == [
        "t.st:30:11: error: type mismatch: cannot pass Cat as Animal [E0401]",
        "t.st:31:14: error: type mismatch: cannot assign Cat to Animal [E0401]",
    ]


def test_an_in_out_reference_or_interface_takes_its_own_type_only() -> None:
    source = """
FUNCTION_BLOCK Keeper
VAR_IN_OUT pet : REF_TO Animal; voice : ISpeaker; END_VAR
VAR spare : Animal; END_VAR
pet := REF(spare);   (* would leave a REF_TO Dog of the caller on an Animal *)
END_FUNCTION_BLOCK
PROGRAM Main
VAR k : Keeper; d : Dog; rd : REF_TO Dog; ra : REF_TO Animal; i : ISpeaker; END_VAR
ra := REF(d); i := d;
k(pet := ra, voice := i);
k(pet := rd, voice := i);
k(pet := ra, voice := d);
END_PROGRAM
"""
    assert errors(source) == [
        "t.st:27:10: error: type mismatch: cannot assign REF_TO Dog to REF_TO Animal [E0401]",
        "t.st:28:23: error: type mismatch: cannot assign Dog to ISpeaker [E0401]",
    ]


def test_an_extended_block_is_not_written_whole_through_an_in_out_or_a_reference() -> None:
    source = """
FUNCTION_BLOCK Vet
VAR_IN_OUT patient : Animal; kitten : Cat; END_VAR
VAR quiet : Animal; other : Cat; r : REF_TO Animal; END_VAR
patient := quiet;
r := REF(quiet);
r^ := quiet;
kitten := other;     (* Cat is extended by no block: a copy fits *)
patient.sound := quiet.sound;
END_FUNCTION_BLOCK
"""
    message = (
        "error: 'Animal' is extended: written whole through an in-out or a reference, it "
        "could replace an instance of a derived block; assign its members [E0314]"
    )
    assert errors(source) == [f"t.st:21:1: {message}", f"t.st:23:1: {message}"]


def test_a_reference_starts_as_null_or_as_ref_of_its_own_instance() -> None:
    source = """
VAR_GLOBAL g : INT; gr : REF_TO INT := REF(g); gn : REF_TO INT := NULL; END_VAR
FUNCTION_BLOCK Box
VAR r : REF_TO INT := REF(n); q : REF_TO INT := NULL; n : INT; END_VAR
END_FUNCTION_BLOCK
PROGRAM Main
VAR a : REF_TO Animal := NULL; x : INT; rx : REF_TO INT := REF(x); END_VAR
VAR rg : REF_TO INT := REF(g); END_VAR
VAR_TEMP t : INT; rt : REF_TO INT := REF(t); END_VAR
x := rx^;
END_PROGRAM
"""
    assert errors(source) == [
        "t.st:24:24: error: initial value of 'rg': a POU's reference can start as a reference "
        "to a variable of its own instance only; set it to REF(g) in the body [E0117]",
        "t.st:25:38: error: REF of 't', a VAR_TEMP (it is gone when the call ends) [E0219]",
    ]
