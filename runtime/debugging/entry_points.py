"""The entry points of the POUs with an armed breakpoint or logpoint (a block's body,
methods, actions and property accessors; a FUNCTION) made to trace themselves while armed
(`tracer.traced_entry`), and put back when nothing is armed in them any more."""

from __future__ import annotations

import functools
from collections.abc import Callable
from types import FunctionType

from runtime.code.code_image import CodeImage
from runtime.debugging.tracer import TraceState, traced_entry


class TracedEntries:
    def __init__(self) -> None:
        self._undo: list[Callable[[], None]] = []

    def install(self, code: CodeImage, filenames: set[str], state: TraceState) -> None:
        """The entry points of the units compiled under `filenames`, traced."""
        self.remove()
        classes = code.classes()
        for filename in sorted(filenames):
            unit = code.units[filename]
            if unit.kind == "FUNCTION":
                original = code.function(unit.name)
                code.replace_function(unit.name, traced_entry(original, state))
                self._undo.append(functools.partial(code.replace_function, unit.name, original))
                continue
            kind = classes.get(unit.class_name)
            for name, member in sorted(vars(kind).items()) if kind is not None else ():
                if (
                    isinstance(member, FunctionType)
                    and name != "__init__"
                    and member.__code__.co_filename == filename
                ):
                    setattr(kind, name, traced_entry(member, state))
                    self._undo.append(functools.partial(setattr, kind, name, member))

    def remove(self) -> None:
        while self._undo:
            self._undo.pop()()
