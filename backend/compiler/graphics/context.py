"""What the lowering of a drawing is told by the file around it: the types of the variables
it may name and of the FUNCTIONs it may call (the drawing keeps a FUNCTION's output in a
variable of its own only when it can tell the type)."""

from __future__ import annotations

from backend.compiler import ast
from backend.compiler.graphics.lower import Context


def context_of(
    pou: ast.Pou, pous: tuple[ast.Pou, ...], globals_: tuple[ast.VarBlock, ...]
) -> Context:
    """The context of `pou`'s drawing, in a file of `pous` and `globals_`."""
    functions = {ast.key(p.name): _type_text(p.return_type) for p in pous if p.kind == "FUNCTION"}
    variables = {**_declared_types(globals_), **_declared_types(pou.var_blocks)}
    if pou.kind == "FUNCTION":
        variables[ast.key(pou.name)] = _type_text(pou.return_type)
    return Context(variables, functions)


def _declared_types(blocks: tuple[ast.VarBlock, ...]) -> dict[str, str]:
    return {ast.key(d.name): _type_text(d.type) for block in blocks for d in block.decls}


def _type_text(type_ref: ast.TypeRef | None) -> str:
    """A declared type as the lowering can name it: an elementary or named type; "" for the
    others (arrays, strings with a length, references)."""
    return type_ref.name if isinstance(type_ref, ast.NamedType) else ""
