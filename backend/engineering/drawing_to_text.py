"""`padt convert`: drawn bodies (FBD, LD) rewritten as the ST the compiler runs for them,
for those who want to leave the drawing. The statements are the drawing's lowering, in its
execution order; the variables the drawing kept between its elements stay, declared, under
the same names, so online values, forces and recordings keep their paths. Nothing is
written unless the whole project still compiles after the change."""

from __future__ import annotations

import re
from dataclasses import dataclass, replace
from pathlib import Path

from backend.compiler import ast
from backend.compiler.diagnostics import CompileError, Diagnostic
from backend.compiler.graphics.context import context_of
from backend.compiler.graphics.lower import Line, lower, temporaries_block
from backend.compiler.parse import parse_as_drawn
from backend.compiler.source import SourceFile
from backend.engineering.project import Project, compile_project

_END = re.compile(r"\bEND_(FBD|LD)\b", re.IGNORECASE)
_END_VAR = re.compile(r"\bEND_VAR\b", re.IGNORECASE)


@dataclass(frozen=True)
class ConvertedPou:
    file: str
    pou: str
    language: str
    elements: int


@dataclass(frozen=True)
class Conversion:
    """What converting a project gives: the POUs converted and the files' new texts, or the
    diagnostics that stopped it (then nothing is written)."""

    converted: tuple[ConvertedPou, ...]
    texts: dict[str, str]
    diagnostics: tuple[Diagnostic, ...]

    @property
    def ok(self) -> bool:
        return not any(d.severity == "error" for d in self.diagnostics)


def convert_project(project: Project, pous: set[str] | None = None) -> Conversion:
    """Every drawn POU of `project` (or those named in `pous`, any case) as ST; the project
    is compiled with the new texts to make sure it still compiles."""
    wanted = {ast.key(p) for p in pous} if pous is not None else None
    texts: dict[str, str] = {}
    converted: list[ConvertedPou] = []
    problems: list[Diagnostic] = []
    for source in project.sources:
        try:
            text, done = converted_text(source.name, source.text, wanted)
        except CompileError as exc:
            problems += exc.diagnostics
            continue
        if done:
            texts[source.name] = text
            converted += done
    if wanted is not None:
        missing = wanted - {ast.key(c.pou.split(".")[0]) for c in converted}
        if missing:
            raise ValueError(f"no drawn POU named {', '.join(sorted(missing))}")
    if problems:
        return Conversion((), {}, tuple(problems))
    sources = [SourceFile(s.name, texts.get(s.name, s.text)) for s in project.sources]
    result = compile_project(replace(project, sources=sources))
    return Conversion(tuple(converted), texts, result.diagnostics)


def write_conversion(folder: Path, conversion: Conversion) -> None:
    for name, text in sorted(conversion.texts.items()):
        (folder / name).write_text(text, encoding="utf-8")


def converted_text(file: str, text: str, wanted: set[str] | None) -> tuple[str, list[ConvertedPou]]:
    """`text` with its drawn POUs (those in `wanted`, upper case; None: all) written as ST:
    the body and the drawn actions of each."""
    pous, globals_ = parse_as_drawn(file, text)
    if wanted is not None:
        pous_wanted = [p for p in pous if ast.key(p.name) in wanted]
    else:
        pous_wanted = list(pous)
    offsets = _line_offsets(text)
    edits: list[tuple[int, int, str]] = []
    done: list[ConvertedPou] = []
    for pou in pous_wanted:
        actions = pou.sfc.actions if pou.sfc is not None else ()
        drawings = [("", pou.graphic)] if pou.graphic is not None else []
        drawings += [(a.name, a.graphic) for a in actions if a.graphic is not None]
        if not drawings:
            continue
        context = context_of(pou, pous, globals_)
        declarations: list[str] = []
        for action, body in drawings:
            lowered = lower(body, file, context, action)
            errors = [d for d in lowered.diagnostics if d.severity == "error"]
            if errors:
                raise CompileError(errors)
            if lowered.temporaries:
                declarations.append(temporaries_block(lowered))
            start = offsets[body.line - 1] + body.col - 1
            end = _END.search(text, start)
            if end is None:  # the parser found it: cannot happen
                raise CompileError([])
            indent = " " * (body.col - 1)
            note = f"(* {body.language} converted to ST by padt convert *)"
            replacement = f"{note}\n{_statements(lowered.lines, indent)}".rstrip("\n")
            edits.append((start, end.end(), replacement))
            what = f"{pou.name}.{action}" if action else pou.name
            done.append(ConvertedPou(file, what, body.language, len(body.elements)))
        if declarations:
            # the hidden variables go after the POU's own (so the variables keep their
            # order), or after its header when it has none
            at = offsets[pou.pos.line]
            if pou.var_blocks:
                last = max(pou.var_blocks, key=lambda b: (b.pos.line, b.pos.col)).pos
                end_var = _END_VAR.search(text, offsets[last.line - 1] + last.col - 1)
                if end_var is not None:
                    at = text.find("\n", end_var.end()) + 1 or len(text)
            edits.append((at, at, "".join(f"{d}\n" for d in declarations)))
    for begin, finish, insert in sorted(edits, reverse=True):
        text = text[:begin] + insert + text[finish:]
    return text, done


def _statements(lines: list[Line], indent: str) -> str:
    return "".join(f"{indent}{line.text}\n" for line in lines)


def _line_offsets(text: str) -> list[int]:
    offsets = [0]
    for line in text.split("\n"):
        offsets.append(offsets[-1] + len(line) + 1)
    return offsets
