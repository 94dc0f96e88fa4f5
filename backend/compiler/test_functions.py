"""The functions of unit tests in ST (docs/testing.md): asserts, and running the resource's
cycles on virtual time from a test. They exist only in test files (below a project's
`test/` folder), which only `padt test` compiles.

Every one becomes a call of the runtime's `_test` intrinsic with the operation's name first
and the place of the call last (file, line, column), so that a failure names where it is.
Under `padt test` the runner answers those calls (backend/engineering/testing/); anywhere
else `_test` is a program error, since no downloaded configuration holds a test file.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

from backend.compiler import ast
from backend.compiler.ast import key
from backend.compiler.codes import Code
from backend.compiler.conversions import intrinsic
from backend.compiler.source import Pos
from backend.compiler.types import BOOL, ELEMENTARY, TIME, ElementaryType, Type, assignable
from runtime.contract.code.statements import Evaluate, Stmt, While
from runtime.contract.code.typed_form import Const, Expr, Unary

TEST_FOLDER = "test/"
UDINT = ELEMENTARY["UDINT"]


def is_test_file(name: str) -> bool:
    """A source of a project's `test/` folder (sources are named by their path in it)."""
    return name.replace("\\", "/").startswith(TEST_FOLDER)


@dataclass(frozen=True)
class TestFunction:
    name: str
    params: tuple[str, ...]
    required: int  # the parameters before the optional MESSAGE
    gives: Type | None = None  # the value of a call; None: a statement only


_MESSAGE = "MESSAGE"
TEST_FUNCTIONS: dict[str, TestFunction] = {
    f.name: f
    for f in (
        TestFunction("ASSERT_TRUE", ("CONDITION", _MESSAGE), 1),
        TestFunction("ASSERT_FALSE", ("CONDITION", _MESSAGE), 1),
        TestFunction("ASSERT_EQUAL", ("EXPECTED", "ACTUAL", _MESSAGE), 2),
        TestFunction("ASSERT_NOT_EQUAL", ("EXPECTED", "ACTUAL", _MESSAGE), 2),
        TestFunction("ASSERT_NEAR", ("EXPECTED", "ACTUAL", "TOLERANCE", _MESSAGE), 3),
        TestFunction("FAIL", (_MESSAGE,), 1),
        TestFunction("RUN_CYCLES", ("N",), 1),
        TestFunction("RUN_FOR", ("T",), 1),
        TestFunction("RUN_UNTIL", ("CONDITION", "T"), 2),
        TestFunction("TEST_CYCLES", (), 0, gives=UDINT),
        TestFunction("FORCE", ("VARIABLE", "VALUE"), 2),
        TestFunction("RELEASE", ("VARIABLE",), 1),
        TestFunction("REPLAY", ("FILE",), 1),
    )
}


def test_function(name: str, file: str) -> TestFunction | None:
    """The test function a call of `name` in `file` calls, if any."""
    return TEST_FUNCTIONS.get(key(name)) if is_test_file(file) else None


class _Scope(Protocol):
    def type_of(self, expr: ast.Expr) -> Type | None: ...
    def report(self, pos: Pos, code: Code, message: str) -> None: ...


def arguments(function: TestFunction, call: ast.Call) -> list[ast.Expr] | str:
    """The arguments in parameter order (positional, or named by the parameters' names), or
    why they do not fit."""
    values = [arg for arg in call.args if arg.value is not None]
    if any(arg.is_output for arg in call.args):
        return f"{function.name} has no outputs"
    if all(arg.name is None for arg in values):
        found: list[ast.Expr] = [arg.value for arg in values if arg.value is not None]
    else:
        by_name = {key(arg.name or ""): arg.value for arg in values}
        unknown = sorted(set(by_name) - set(function.params) - {""})
        if unknown or "" in by_name:
            return f"{function.name}: name every argument or none ({', '.join(function.params)})"
        found = []
        for param in function.params:
            value = by_name.get(param)
            if value is None:
                break
            found.append(value)
    if not function.required <= len(found) <= len(function.params):
        wanted = ", ".join(
            p if i < function.required else f"[{p}]" for i, p in enumerate(function.params)
        )
        return f"{function.name}({wanted}): {len(found)} arguments do not fit"
    return found


def check_test_call(scope: _Scope, call: ast.Call, function: TestFunction) -> None:
    """The arguments of a test function: their number, and the types each one takes."""
    found = arguments(function, call)
    if isinstance(found, str):
        scope.report(call.pos, Code.TEST_FUNCTION, found)
        return
    named = dict(zip(function.params, found, strict=False))
    types = {param: scope.type_of(value) for param, value in named.items()}

    def want(param: str, fits: bool, what: str) -> None:
        if param in types and types[param] is not None and not fits:
            found_type = types[param]
            assert found_type is not None
            scope.report(
                named[param].pos,
                Code.TEST_FUNCTION,
                f"{function.name}: {param} must be {what}, not {found_type.name}",
            )

    def category(param: str) -> str:
        t = types.get(param)
        return t.category if isinstance(t, ElementaryType) else ""

    want(_MESSAGE, category(_MESSAGE) == "string", "a STRING")
    want("FILE", category("FILE") == "string", "a STRING (the recording's path in the project)")
    want("CONDITION", types.get("CONDITION") == BOOL, "BOOL")
    want("N", category("N") == "int", "an integer")
    want("T", types.get("T") == TIME, "a TIME")
    if function.name in ("ASSERT_EQUAL", "ASSERT_NOT_EQUAL", "FORCE"):
        first, second = (
            ("VALUE", "VARIABLE") if function.name == "FORCE" else ("EXPECTED", "ACTUAL")
        )
        target = types.get(second)
        if target is not None and types.get(first) is not None:
            source = types[first]
            assert source is not None
            if not assignable(target, source):
                scope.report(
                    named[first].pos,
                    Code.TEST_FUNCTION,
                    f"{function.name}: {first} is {source.name}, {second} is {target.name}: "
                    "give both the same type",
                )
    if function.name == "ASSERT_NEAR":
        for param in ("EXPECTED", "ACTUAL", "TOLERANCE"):
            want(param, category(param) in ("real", "int"), "a number")
    if function.name in ("FORCE", "RELEASE"):
        variable = named.get("VARIABLE")
        if variable is not None and place_path(variable) is None:
            scope.report(
                variable.pos,
                Code.TEST_FUNCTION,
                f"{function.name}: VARIABLE must name a variable of a program or a global "
                "(Program.name, Program.instance.member, a global)",
            )


def place_path(expr: ast.Expr) -> str | None:
    """The resource path a test names a variable by (`Main.fb.x`, `arr[2]`), as spelled;
    the runner finds the variable whatever its case. None for anything else."""
    match expr:
        case ast.NameRef(name=name):
            return name
        case ast.MemberRef(base=base, member=member):
            below = place_path(base)
            return None if below is None else f"{below}.{member}"
        case ast.IndexRef(base=base, indices=indices) if all(
            isinstance(i, ast.IntLiteral) for i in indices
        ):
            below = place_path(base)
            if below is None:
                return None
            numbers = [str(i.value) for i in indices if isinstance(i, ast.IntLiteral)]
            return f"{below}[{', '.join(numbers)}]"
    return None


class _Emitter(Protocol):
    def exact_node(self, expr: ast.Expr) -> Expr: ...
    def converted(self, target: Type, value_expr: ast.Expr) -> Expr: ...
    def type_of(self, expr: ast.Expr) -> Type: ...


def test_call_statements(
    emitter: _Emitter, call: ast.Call, function: TestFunction, line: int
) -> list[Stmt]:
    """The generated statements of a test function's call; the place of the call ends
    every `_test` call."""
    found = arguments(function, call)
    assert not isinstance(found, str), found
    named = dict(zip(function.params, found, strict=False))
    at = (Const(call.pos.file, "STRING"), Const(call.pos.line, "DINT"), Const(call.pos.col, "DINT"))

    def node(param: str) -> Expr:
        return emitter.exact_node(named[param])

    def test(*values: Expr) -> Evaluate:
        return Evaluate(intrinsic("_test", "", *values, *at), line)

    def word(text: str) -> Const:
        return Const(text, "STRING")

    message = node(_MESSAGE) if _MESSAGE in named else word("")
    match function.name:
        case "ASSERT_TRUE" | "ASSERT_FALSE":
            op = "true" if function.name == "ASSERT_TRUE" else "false"
            return [test(word(op), node("CONDITION"), message)]
        case "ASSERT_EQUAL" | "ASSERT_NOT_EQUAL" | "ASSERT_NEAR":
            op = {"ASSERT_EQUAL": "equal", "ASSERT_NOT_EQUAL": "not_equal"}.get(
                function.name, "near"
            )
            actual_type = emitter.type_of(named["ACTUAL"])
            expected = emitter.converted(actual_type, named["EXPECTED"])
            tolerance = (node("TOLERANCE"),) if op == "near" else ()
            values = (expected, node("ACTUAL"), *tolerance, word(actual_type.name))
            return [test(word(op), *values, message)]
        case "FAIL":
            return [test(word("fail"), message)]
        case "RUN_CYCLES":
            return [test(word("cycles"), node("N"))]
        case "RUN_FOR":
            return [test(word("for"), node("T"))]
        case "RUN_UNTIL":  # the condition is read again after every cycle
            until = test(word("until"), node("T"))
            condition = node("CONDITION")
            return [until, While(Unary("not", condition, "BOOL"), (test(word("step")),), line)]
        case "FORCE":
            path = place_path(named["VARIABLE"])
            variable_type = emitter.type_of(named["VARIABLE"])
            value = emitter.converted(variable_type, named["VALUE"])
            return [test(word("force"), Const(path, "STRING"), value)]
        case "RELEASE":
            return [test(word("release"), Const(place_path(named["VARIABLE"]), "STRING"))]
        case "REPLAY":
            return [test(word("replay"), node("FILE"))]
    raise AssertionError(function.name)


TEST_CYCLES_CALL = intrinsic("_test", "DINT", Const("count", "STRING"))
