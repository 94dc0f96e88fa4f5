"""A configuration's values moved into its memory image, and back to objects
(docs/native-code.md, "The tier switch"): between two cycles, every value kept, every
place that holds an instance given the view (or the object) in its stead: the programs'
instances and their views of the globals, the globals (`_G`), the programs ST calls by
name (`_P`). The services then reach the values through `ImageMemory` (or `ObjectMemory`),
and a reading plan made before is made again (`Variables.bound` is a new list).

The resource moves the values into the image once the tier's C for it is in place
(`Resource.tier_up`), and back to objects while it is debugged, while a reload plans and
before a program restarts.
"""

from __future__ import annotations

from typing import Any

from runtime.code.native.image_plan import ImagePlan
from runtime.contract.refusal import Refusal
from runtime.image_memory import ImageMemory
from runtime.memory import ObjectMemory
from runtime.variables import Variables


def enter_image(variables: Variables, plan: ImagePlan) -> bytearray:
    """The values of `variables`' objects into a new image of `plan`, and its views in
    their places; the image."""
    code = _idle(variables)
    image = bytearray(plan.placement.size)
    views = {
        p.name: plan.views[p.cls](image, p.offset)
        for p in plan.placement.placements
        if p.cls in plan.views
    }
    # every value packed (in C, all at once: an in-out is bound where its variable went)
    # before any instance is replaced: a value a view refuses (of another type, out of its
    # range) leaves the configuration as it was
    held = [(views[name], instance) for name, instance in _held(variables).items()]
    plan.memory.pack(held, plan.in_outs)
    _move(variables, views)
    variables.memory = ImageMemory(
        image, plan.layouts, plan.placement, plan.class_names, [p.name for p in variables.programs]
    )
    variables.bound = list(variables.bound)
    variables.image = plan
    assert code is variables.code
    return image


def leave_image(variables: Variables) -> None:
    """The values of the image into fresh objects of the generated classes, in their
    places (the reverse of `enter_image`)."""
    code = _idle(variables)
    assert variables.image is not None, "the values are on objects"
    held = _held(variables)
    pous = {program.name: program.config.pou for program in variables.programs}
    # every object made before a value is copied: making one may run code (FB_INIT)
    fresh = {
        name: code.new_globals()
        if name == "_G" or name.endswith("._G")  # the globals or a program's copy of them
        else code.new_instance(pous.get(name) or name.removeprefix("_P."))
        for name in held
    }
    # every value, in C, all at once: an in-out gets the object unpacked where it is bound
    pairs = [(view, fresh[name]) for name, view in held.items()]
    variables.image.memory.unpack(pairs, variables.image.in_outs)
    _move(variables, fresh)
    variables.memory = ObjectMemory(variables.globals, variables.programs)
    variables.bound = list(variables.bound)
    variables.image = None


def must_leave(variables: Variables) -> bool:
    """Whether the values must go back to objects now: they are in the image while the
    code runs as Python for the debugger (its breakpoints know instances by identity, and
    a view is a new object at each access), and no program is in the middle of its program
    cycle (a sliced one is left once its cycle ends)."""
    code = variables.code
    return (
        variables.image is not None
        and code is not None
        and code.python_only
        and not any(program.in_progress for program in variables.programs)
    )


def may_enter(variables: Variables) -> ImagePlan | None:
    """The plan of the running code's image, when its values may go there now: between two
    program cycles, not while the resource is debugged (the debugger knows instances by
    identity, a view is a new object at each access) nor while a reload plans against the
    objects."""
    code = variables.code
    if code is None or code.image is None or variables.image is not None or code.python_only:
        return None
    if variables.image_held is not None:
        if variables.image_held() is not None:
            return None
        variables.image_held = None
    if any(program.in_progress for program in variables.programs):
        return None
    return code.image


def _idle(variables: Variables) -> Any:
    code = variables.code
    assert code is not None
    busy = [p.name for p in variables.programs if p.in_progress]
    if busy:  # a suspended program cycle's frame holds the instances it began with
        raise Refusal("busy", f"program {busy[0]} is in the middle of its program cycle; try again")
    return code


def _run(variables: Variables) -> set[str]:
    return {program.config.pou.upper() for program in variables.programs}


def _held(variables: Variables) -> dict[str, Any]:
    """Every instance `_move` replaces, by the name it has in the image's placement."""
    code = variables.code
    assert code is not None
    held = {"_G": variables.globals} if variables.globals is not None else {}
    for program in variables.programs:
        held[program.name] = program.instance
        if program.view is not variables.globals:
            held[f"{program.name}._G"] = program.view
    for pou in code.artifact.pous:
        if pou.kind == "PROGRAM" and pou.name.upper() not in _run(variables):
            held[f"_P.{pou.name}"] = code.program_instance(pou.name)
    return held


def _move(variables: Variables, replacements: dict[str, Any]) -> None:
    """Each instance of `variables` replaced by the one of the same name in
    `replacements` (`_held`'s names), in every place that holds it."""
    code = variables.code
    assert code is not None
    old_globals = variables.globals
    new_globals = replacements["_G"] if old_globals is not None else None
    for program in variables.programs:
        instance = replacements[program.name]
        code.adopt_program(program.instance, instance)
        program.instance = instance
        if program.view is old_globals:
            program.view = new_globals
        else:
            program.view = replacements[f"{program.name}._G"]
    for pou in code.artifact.pous:
        if pou.kind == "PROGRAM" and pou.name.upper() not in _run(variables):
            code.adopt_program(code.program_instance(pou.name), replacements[f"_P.{pou.name}"])
    if new_globals is not None:
        code.adopt_globals(new_globals)
    variables.globals = new_globals
