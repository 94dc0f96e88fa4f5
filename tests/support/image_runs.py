"""The Python tier's code run twice side by side, on slot objects and on views of a memory
image (runtime/code/native/image_views.py), on a virtual time: what a body left to Python
will see once the image is live, compared with what it sees today."""

from __future__ import annotations

import struct
from types import ModuleType
from typing import Any

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.code.code_image import CodeImage
from runtime.code.instances import Instances, instances_of
from runtime.code.intrinsics import SystemView, _ActionControl, _SfcStep
from runtime.code.native.image_views import copy_into, view_classes
from runtime.contract.artifact import Artifact
from runtime.contract.layout import (
    ACTION_CONTROL,
    HEADER,
    SFC_STEP,
    class_layouts,
    image_layout,
    runtime_layouts,
)

CYCLE_NS = 100_000_000


def compiled(text: str) -> Artifact:
    result = compile_sources([SourceFile("prog.st", text)])
    assert result.artifact is not None, [str(d) for d in result.diagnostics]
    return result.artifact


def values(instance: Any) -> Any:
    """An instance's values as plain data: a dict per instance, a list per array, a REAL's
    bytes (NaN equal to NaN, bit for bit)."""
    if isinstance(instance, float):
        return struct.pack("<d", instance)
    if instance is None or isinstance(instance, bool | int | str):
        return instance
    if isinstance(instance, list) or type(instance).__name__ == "Elements":
        return [values(item) for item in instance]
    return {name: values(getattr(instance, name)) for name in type(instance).__slots__}


class ImageRun:
    """One configuration on objects and on an image, each cycled alike."""

    def __init__(self, artifact: Artifact, memory: ModuleType) -> None:
        self.system = SystemView()
        self.objects = instances_of(CodeImage(artifact, self.system))
        self.viewed = instances_of(CodeImage(artifact, self.system))
        layouts = {**runtime_layouts(), **class_layouts(artifact.units())}
        classes = {
            **self.viewed.image.classes(),
            SFC_STEP: _SfcStep,
            ACTION_CONTROL: _ActionControl,
            HEADER: SystemView,
        }
        views = view_classes(memory, layouts, classes)
        placement = image_layout(artifact, layouts)
        self.image = bytearray(placement.size)
        placed = {p.name: views[p.cls](self.image, p.offset) for p in placement.placements}
        if self.viewed.globals is not None:
            copy_into(placed["_G"], self.viewed.globals)
        for program in self.viewed.programs:
            copy_into(placed[program.name], program.instance)
            program.instance = placed[program.name]
            shared = program.view is self.viewed.globals
            program.view = placed["_G"] if shared else placed[f"{program.name}._G"]
        self.viewed.globals = placed.get("_G")
        self.cycles = 0

    def cycle(self) -> tuple[str, str]:
        """One cycle of both; the fault each had ("" for none)."""
        self.cycles += 1
        self.system.now_ns = self.cycles * CYCLE_NS
        return _cycle(self.objects), _cycle(self.viewed)

    def compare(self) -> None:
        for on_objects, on_views in zip(self.objects.programs, self.viewed.programs, strict=True):
            assert values(on_objects.instance) == values(on_views.instance), self.cycles
        assert values(self.objects.globals) == values(self.viewed.globals), self.cycles


def _cycle(instances: Instances) -> str:
    for program in instances.programs:
        instances.image.use(program.view, None)
        try:
            program.instance.__call__()
        except Exception as fault:  # a program fault, to be the same on both
            return f"{type(fault).__name__}: {fault}"
    return ""
