"""The stable codes of the compiler's diagnostics, each listed once with a short title.

A code names one kind of problem and keeps its meaning across releases, so that tools and
people can refer to it; the message around it may change. Errors are `E` and warnings `W`
followed by four digits, grouped by hundreds: 00 syntax and literals, 01 declarations,
02 names, types and expressions, 03 statements and assignments, 04 calls, 05 sequential
function charts, 06 the resource (user programs, safe values, users, Modbus, OPC UA), 07 what
padt does not compile (features it lacks, limits), 08 extensions of other dialects (CODESYS,
TwinCAT) that padt accepts, each with a warning that it is not IEC 61131-3, 09 graphical
bodies (FBD, LD), 10 unit tests.
Notes (`N`) tell what was ignored without changing what the program does.
docs/diagnostics.md explains every code with a failing and a passing example.
"""

from __future__ import annotations

from enum import Enum, unique
from typing import Literal

Severity = Literal["error", "warning", "note"]


@unique
class Code(Enum):
    def __init__(self, id: str, title: str) -> None:
        self.id = id  # E0123 or W0123
        self.title = title

    @property
    def severity(self) -> Severity:
        severities: dict[str, Severity] = {"E": "error", "W": "warning", "N": "note"}
        return severities[self.id[0]]

    # ---- 00: syntax and literals
    SYNTAX = "E0001", "syntax error"
    STRING_ESCAPE = "E0002", "invalid escape in a string literal"
    INVALID_LITERAL = "E0003", "literal without a value"
    IDENTIFIER = "E0004", "identifier with two underscores in a row or one at its end"
    PRAGMA_SKIPPED = "W0001", "pragma skipped"
    UNPARSED_FILE = "N0001", "a file that did not parse, before the errors it may cause"

    # ---- 01: declarations
    DUPLICATE_TYPE = "E0101", "type declared twice"
    DUPLICATE_GLOBAL = "E0102", "global variable declared twice"
    DUPLICATE_POU = "E0103", "POU declared twice"
    DUPLICATE_VARIABLE = "E0104", "variable declared twice in a POU"
    DUPLICATE_ENUM_VALUE = "E0105", "enum value declared twice"
    DUPLICATE_MEMBER = "E0106", "structure member declared twice"
    UNKNOWN_TYPE = "E0107", "unknown type"
    RECURSIVE_TYPE = "E0108", "type defined in terms of itself"
    SELF_CONTAINED = "E0109", "function block that contains an instance of itself"
    EXTERNAL_WITHOUT_GLOBAL = "E0110", "VAR_EXTERNAL without a VAR_GLOBAL"
    STRING_LENGTH = "E0111", "string length not a positive constant"
    ARRAY_BOUNDS = "E0112", "array bounds not constant integers"
    EMPTY_ARRAY_RANGE = "E0113", "empty array range"
    ENUM_BASE = "E0114", "enum base type not an integer type"
    ENUM_VALUE = "E0115", "enum value not a constant integer"
    EDGE_INPUT = "E0116", "R_EDGE or F_EDGE on something else than a BOOL input"
    NOT_CONSTANT_INITIAL = "E0117", "initial value not a constant expression"
    ARRAY_INITIALIZER = "E0118", "array initializer for something else than an array"
    STRUCT_INITIALIZER = "E0119", "structure initializer for something else than a structure"
    REPETITION_COUNT = "E0120", "repetition count not an integer literal"
    TOO_MANY_INITIAL_VALUES = "E0121", "more initial values than array elements"
    GENERATED_NAME = "E0122", "name the generated code uses itself"
    SUBRANGE_BASE = "E0123", "subrange of something else than an integer type"
    SUBRANGE_BOUNDS = "E0124", "subrange bounds not constant integers of the base type"
    EMPTY_SUBRANGE = "E0125", "empty subrange"
    METHOD_NAME = "E0126", "method named like a variable or another method"
    EXTENDS = "E0127", "EXTENDS of something else than one function block"
    CYCLIC_EXTENDS = "E0128", "function block that extends itself"
    FINAL_OVERRIDE = "E0129", "override of a FINAL method or extension of a FINAL block"
    ABSTRACT_INSTANCE = "E0130", "instance of an ABSTRACT function block"
    ABSTRACT_METHOD = "E0131", "ABSTRACT method with a body or left without one"
    OVERRIDE_SIGNATURE = "E0132", "method that overrides with another signature"
    INTERFACE = "E0133", "IMPLEMENTS or EXTENDS of something that is no interface"
    INTERFACE_METHOD = "E0134", "interface method not implemented as declared"
    MEMBER_OWNER = "E0135", "method or property after no block or interface"
    SPECIFIER = "E0136", "access specifier or modifier that does not apply to a declaration"
    LOCATION_AREA = "E0137", "location without an area (I, Q or M)"

    # ---- 02: names, types and expressions
    UNDECLARED = "E0201", "name not declared"
    SYSTEM_NAMESPACE = "E0202", "SYS without the name of a system variable"
    UNKNOWN_SYSTEM_VARIABLE = "E0203", "unknown system variable"
    NO_MEMBER = "E0204", "no such member"
    NOT_AN_ENUM = "E0205", "typed literal of a type that is no enum"
    NO_ENUM_VALUE = "E0206", "enum has no such value"
    UNKNOWN_LITERAL_TYPE = "E0207", "typed literal of an unknown type"
    LITERAL_KIND = "E0208", "typed literal of the wrong kind"
    TYPE_MISMATCH = "E0209", "value of the wrong type"
    OUT_OF_RANGE = "E0210", "integer literal out of the range of its type"
    OPERATOR_TYPES = "E0211", "operator that does not apply to its operands"
    INDEX_TYPE = "E0212", "array index not an integer"
    NOT_AN_ARRAY = "E0213", "index on something else than an array"
    INDEX_COUNT = "E0214", "wrong number of array indices"
    INDEX_OUT_OF_BOUNDS = "E0215", "constant array index outside the bounds"
    BIT_ACCESS_TYPE = "E0216", "bit access on something else than an integer"
    BIT_OUT_OF_RANGE = "E0217", "bit access beyond the width of the value"
    NOT_A_REFERENCE = "E0218", "dereference of something that is no reference"
    REFERENCE_TARGET = "E0219", "reference to something that is no lasting variable"
    REFERENCE_BINDING = "E0220", "misused REFERENCE TO"
    THIS_SUPER = "E0221", "THIS or SUPER where there is none, or SUPER without ^"
    EXPLICIT_CONVERSION = "E0222", "conversion that needs a conversion function"

    # ---- 03: statements and assignments
    ASSIGN_CONSTANT = "E0301", "assignment to a constant"
    ASSIGN_NON_VARIABLE = "E0302", "assignment to an enum value or a program"
    ASSIGN_EXPRESSION = "E0303", "assignment to an expression"
    ASSIGN_MEMBER_OF_VALUE = "E0304", "assignment to a member of a value"
    FB_MEMBER_WRITE = "E0305", "function block member not writable from outside"
    SYSTEM_VARIABLE_WRITE = "E0306", "write to a read-only system variable"
    CONDITION_TYPE = "E0307", "condition not BOOL"
    OUTSIDE_LOOP = "E0308", "EXIT or CONTINUE outside of a loop"
    CASE_SELECTOR_TYPE = "E0309", "CASE selector not an integer or enum"
    CASE_LABEL_TYPE = "E0310", "CASE label not an integer or enum"
    CASE_LABEL_TWICE = "E0311", "CASE label used twice"
    FOR_COUNTER_TYPE = "E0312", "FOR counter not an integer"
    PROPERTY_ACCESSOR = "E0313", "property read without GET or written without SET"
    CUT_INSTANCE = "E0314", "extended block's instance written whole through in-out or reference"
    INPUT_ASSIGNMENT = "W0301", "assignment to an input inside its block"

    # ---- 04: calls
    ARGUMENT_TYPE = "E0401", "argument of the wrong type"
    OUTPUT_TYPE = "E0402", "output stored in a variable of the wrong type"
    NO_PARAMETER = "E0403", "no such parameter"
    TOO_MANY_ARGUMENTS = "E0404", "too many arguments"
    MISSING_ARGUMENTS = "E0405", "missing arguments of a standard function"
    STANDARD_ARGUMENTS = "E0406", "arguments a standard function does not take"
    INPUT_AS_OUTPUT = "E0407", "input connected as an output"
    IN_OUT_VARIABLE = "E0408", "in-out argument that is no variable"
    INSTANCE_VALUE = "E0409", "function block instance used as a value"
    PROGRAM_VALUE = "E0410", "program used as a value"
    NOT_A_FUNCTION = "E0411", "call of something that is no function"
    EXTERNAL_FUNCTION = "E0412", "external function that is not available"
    OPEN_ARRAY_UNCONNECTED = "E0413", "variable-length array parameter left unconnected"
    METHOD_ACCESS = "E0414", "method its access specifier hides here"
    METHOD_VALUE = "E0415", "method without a result used as a value"
    NO_METHOD = "E0416", "call of a method the block does not have"
    IN_OUT_TYPE = "E0417", "in-out argument of another type than its parameter"

    # ---- 05: sequential function charts
    INITIAL_STEP = "E0501", "step chain without exactly one initial step"
    STEP_NAME = "E0502", "step name already used"
    DUPLICATE_ACTION = "E0503", "action declared twice"
    STEP_FLAG_WRITE = "E0504", "write to a step flag"
    UNKNOWN_ACTION = "E0505", "association with neither an action nor a BOOL variable"
    UNKNOWN_QUALIFIER = "E0506", "unknown action qualifier"
    QUALIFIER_NEEDS_TIME = "E0507", "timed qualifier without a time"
    QUALIFIER_TIME_TYPE = "E0508", "time of a qualifier that is no TIME"
    QUALIFIER_TAKES_NO_TIME = "E0509", "time for a qualifier that takes none"
    UNKNOWN_STEP = "E0510", "transition from or to an unknown step"
    ACTIONS_OWNER = "E0511", "ACTIONS block of no PROGRAM or FUNCTION_BLOCK"
    ACTION_CALL_ARGUMENTS = "E0512", "action called with arguments"
    ACTION_NAME = "E0513", "action named like a variable of its POU"
    ACTION_VALUE = "E0514", "action used as a value"

    # ---- 06: the resource: user programs, safe values, users
    PROGRAM_POU = "E0601", "user program without its PROGRAM"
    PROGRAM_ID_RANGE = "E0602", "program ID outside 1..32"
    PROGRAM_ID_TAKEN = "E0603", "program ID used twice"
    TOO_MANY_PROGRAMS = "E0604", "more than 32 user programs"
    SLICES_EXCEED_WATCHDOG = "E0605", "time slices longer than the watchdog time"
    SECOND_WRITER = "E0606", "global written by more than one user program"
    SAFE_VALUE_TARGET = "E0607", "safe value for something else than a global output"
    SAFE_VALUE = "E0608", "safe value that is no value of the output's type"
    USER_ACCOUNT = "E0609", "invalid user account"
    DUPLICATE_USER = "E0610", "user defined twice"
    NO_ADMINISTRATOR = "E0611", "users without an administrator"
    MODBUS_SETTING = "E0612", "invalid Modbus setting"
    MODBUS_VARIABLE = "E0613", "Modbus point on no suitable located variable"
    MODBUS_TYPE = "E0614", "Modbus point its table cannot hold"
    MODBUS_OVERLAP = "E0615", "Modbus address or input mapped twice"
    UNCONFIGURED_LOCATION = "E0616", "partly specified location without its address"
    VAR_CONFIG_PATH = "E0617", "VAR_CONFIG for no partly located variable"
    VAR_CONFIG_ADDRESS = "E0618", "VAR_CONFIG entry that does not fit its variable"
    ACCESS_PATH = "E0619", "access path to no variable of its type"
    RESOURCE_NAME = "E0620", "resource name that is no plain identifier"
    OPCUA_SETTING = "E0621", "invalid OPC UA setting"
    OPCUA_PATH = "E0622", "OPC UA path to no variable of the resource"
    OPCUA_WRITABLE = "E0623", "writable OPC UA path that is not exposed or is a constant"
    OPCUA_ENDPOINT = "E0624", "OPC UA endpoint that is no opc.tcp address"
    OPCUA_NODE = "E0625", "OPC UA node id that does not read"
    OPCUA_VARIABLE = "E0626", "OPC UA point on no suitable located variable"
    OPCUA_MAPPED_TWICE = "E0627", "variable mapped by two device points"
    EXCHANGE_SETTING = "E0628", "invalid exchange setting"
    EXCHANGE_VARIABLE = "E0629", "exchange of no suitable global variable"
    EXTRA_RESOURCE = "W0601", "resource ignored"
    PROGRAM_ARGUMENTS = "W0602", "program arguments in a configuration ignored"

    # ---- 07: what padt does not compile
    POINTERS = "E0701", "pointer arithmetic"
    DIRECT_ADDRESS = "E0703", "direct address of another POU's variable"
    VARIABLE_LENGTH_ARRAY = "E0704", "variable-length array where it cannot be"
    STATEMENT_DEPTH = "E0705", "statements nested too deep"
    EXPRESSION_DEPTH = "E0706", "expression nested too deep"
    FILE_SIZE = "E0707", "source file too large"
    PROJECT_SIZE = "E0708", "project too large"
    LITERAL_LENGTH = "E0709", "literal too long"
    ARRAY_SIZE = "E0710", "array too large"
    DATA_DEPTH = "E0711", "data types nested too deep"
    DATA_SIZE = "E0712", "too much data"
    CODE_SIZE = "E0713", "generated code too large"
    METHOD_STATIC = "E0714", "static variables of a method (VAR_INST, VAR_STAT)"
    IMPLICIT_METHOD = "E0715", "FB_INIT, FB_REINIT or FB_EXIT, which CODESYS calls by itself"
    STRUCT_LOCATION = "E0716", "location of a structure member"
    PROGRAM_SCOPE_BLOCK = "E0717", "VAR_GLOBAL or VAR_ACCESS inside a PROGRAM"

    # ---- 09: graphical bodies (FBD, LD)
    GRAPHIC_SYNTAX = "E0901", "element line of a graphical body that does not read"
    GRAPHIC_WIRE = "E0902", "wire from an element or pin that is not there"
    GRAPHIC_FEEDBACK = "E0904", "feedback loop through a FUNCTION's output"
    GRAPHIC_LABEL = "E0905", "jump to a label that is not there, or a name given twice"
    GRAPHIC_NAME = "E0906", "variable named like one the lowering of a drawing needs"
    GRAPHIC_KIND = "E0907", "element of LD in an FBD body"
    GRAPHIC_UNCONNECTED = "W0901", "element without the wire it acts on, left out"

    # ---- 10: unit tests (test files, docs/testing.md)
    TEST_FUNCTION = "E1001", "test function called with arguments it does not take"
    TEST_VALUE = "E1002", "test function used as a value"

    # ---- 08: extensions of other dialects, accepted with a warning
    QUALIFIED_ENUM = "W0801", "qualified enumeration value E.Value (CODESYS/TwinCAT)"
    SIZEOF = "W0802", "SIZEOF (CODESYS/TwinCAT)"
    SET_RESET_ASSIGNMENT = "W0803", "S= or R= assignment (CODESYS/TwinCAT)"
    TRAILING_COMMA = "W0804", "trailing comma in a call (CODESYS/TwinCAT)"
    POINTER = "W0805", "POINTER TO and ADR (CODESYS/TwinCAT)"
    IMPLICIT_REFERENCE = "W0806", "REFERENCE TO and REF= (CODESYS/TwinCAT)"
    EXPRESSION_STATEMENT = "W0807", "expression as a statement (CODESYS/TwinCAT)"
    NON_FINITE_CONSTANT = "W0808", "INF_REAL, NAN_REAL, INF_LREAL, NAN_LREAL (rusty)"
    PUBLIC_POU = "W0809", "PUBLIC on a POU, interface or data type (CODESYS/TwinCAT)"
    LOCATED_PARAMETER = "W0810", "AT %I*, %Q* on an input or output of a block (TwinCAT)"
    IMPLICIT_NUMERIC_CONVERSION = "W0811", "implicit conversion between numbers (CODESYS/TwinCAT)"
    ATTRIBUTE_PRAGMA = "N0801", "pragma ignored (CODESYS/TwinCAT)"
    INTERNAL_POU = "N0802", "INTERNAL outside a namespace (CODESYS/TwinCAT libraries)"
    QUALIFIED_NAME = "N0803", "name qualified by a library namespace or global list (CODESYS)"
    SIZEOF_ARGUMENT = "E0801", "SIZEOF of something without a CODESYS size"
