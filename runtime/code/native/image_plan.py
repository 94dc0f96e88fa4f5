"""Whether a configuration's values can go into a memory image, and what that takes: its
layouts, where each instance lies, a view class per class (docs/native-code.md,
"Variables in native memory"). All or nothing per configuration: where any class has no
layout or no view yet (a reference, an interface, an in-out of an aggregate), the
configuration stays on objects, and the reason is said."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any

from runtime.code.intrinsics import _ActionControl, _SfcStep
from runtime.code.native.build import Toolchain
from runtime.code.native.image_views import ViewsRefused, memory_module, view_classes
from runtime.contract.artifact import Artifact
from runtime.contract.layout import (
    ACTION_CONTROL,
    HEADER,
    SFC_STEP,
    Bound,
    ImageLayout,
    LayoutRefused,
    Layouts,
    class_layouts,
    image_layout,
    runtime_layouts,
)


@dataclass(frozen=True)
class ImagePlan:
    """A configuration's image: its layouts, where each instance lies, the view class of
    each class and the name the class has in Python (which the context's trees name);
    `registry`, the C bodies the modules bound to it registered (image_body.py)."""

    layouts: Layouts
    placement: ImageLayout
    views: dict[str, type]
    class_names: dict[str, str]
    memory: ModuleType  # padt_memory
    # whether a class has a block's in-out (`Bound`), which the moves between objects and
    # the image bind through an identity map
    in_outs: bool
    registry: dict[str, Any] = field(default_factory=dict)


def plan_image(
    artifact: Artifact, classes: Mapping[str, type], cache: Path, toolchain: Toolchain
) -> ImagePlan | str:
    """The image of `artifact`, whose generated classes are `classes` (by class name, as
    `CodeImage.classes` gives them); or why it has none."""
    try:
        layouts = {**runtime_layouts(), **class_layouts(artifact.units())}
        placement = image_layout(artifact, layouts)
    except LayoutRefused as refused:
        return f"no layout: {refused}"
    known = {**classes, SFC_STEP: _SfcStep, ACTION_CONTROL: _ActionControl}
    viewed = {name: layout for name, layout in layouts.items() if name != HEADER}
    missing = sorted(set(viewed) - set(known))
    if missing:
        return f"no class {missing[0]}"
    memory = memory_module(cache, toolchain)
    try:
        views = view_classes(memory, viewed, known)
    except ViewsRefused as refused:
        return f"no view: {refused}"
    names = {name: known[name].__name__ for name in viewed}
    in_outs = any(isinstance(m.shape, Bound) for lay in layouts.values() for m in lay.members)
    return ImagePlan(layouts, placement, views, names, memory, in_outs)
