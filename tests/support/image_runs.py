"""The Python tier's code run twice side by side, on slot objects and on views of a memory
image (runtime/code/native/image_views.py), on a virtual time: what a body left to Python
will see once the image is live, compared with what it sees today."""

from __future__ import annotations

import math
import struct
from types import ModuleType
from typing import Any

from backend.compiler.pipeline import compile_sources
from backend.compiler.source import SourceFile
from runtime.code.code_image import CodeImage
from runtime.code.instances import Instances, instances_of
from runtime.code.intrinsics import SystemView, _ActionControl, _SfcStep
from runtime.code.native.build import build, load
from runtime.code.native.image_body import translate_image_unit
from runtime.code.native.image_views import view_classes
from runtime.code.native.tier import NativeTier, _breathe
from runtime.code.native.worker import ArtifactTranslation
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
    bytes (bit for bit; every NaN one value, as tests/support/native_runs.py's `same` has
    it: C may give a NaN the other sign, `x / -y` as `-(x / y)`)."""
    if isinstance(instance, float):
        return "NaN" if math.isnan(instance) else struct.pack("<d", instance)
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
        self.memory, self.layouts, self.views = memory, layouts, views
        self.registry: dict[str, Any] = {}  # of the C bodies bound to this run (with_c_bodies)
        self.class_names = {name: kind.__name__ for name, kind in classes.items()}
        self.placement = placement = image_layout(artifact, layouts)
        self.image = bytearray(placement.size)
        placed = {p.name: views[p.cls](self.image, p.offset) for p in placement.placements}
        held = [(placed[program.name], program.instance) for program in self.viewed.programs]
        if self.viewed.globals is not None:
            held.append((placed["_G"], self.viewed.globals))
        memory.pack(held)
        for program in self.viewed.programs:
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
        except Exception as fault:  # a program fault, to be the same on both, at one place
            return f"{type(fault).__name__}: {fault} at {instances.image.locate(fault)}"
    return ""


def with_c_bodies(run: ImageRun, tier: NativeTier) -> list[tuple[str, str]]:
    """The bodies of `run`'s image translated in image mode, built and put in place on the
    view classes; the bodies left to Python, with the reasons."""
    assert tier.toolchain is not None
    artifact = run.viewed.image.artifact
    translation = ArtifactTranslation.of(artifact)
    registry: dict[str, Any] = run.registry  # the modules' statics borrow it
    namespace = run.viewed.image.namespace  # what the tier binds modules to
    left: list[tuple[str, str]] = []
    for unit in translation.units:
        form = translation.forms[unit.class_name]
        translated = translate_image_unit(
            unit,
            form,
            translation.classes,
            translation.globals_class,
            run.layouts,
            translation.functions,
        )
        left.extend(translated.left)
        if not translated.source:
            continue
        path = build(translated.module, translated.source, tier.cache, tier.toolchain)
        module = load(translated.module, path)
        bodies = module.bind(namespace, _breathe, run.views, registry, run.memory.View)
        for (cls, name), body in bodies.items():
            setattr(run.views[cls], name, body)
    return left
