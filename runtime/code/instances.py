"""The executable side of a configuration: its code, the program and global instances, and
every elementary variable bound to what it belongs to."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from types import CodeType
from typing import Any

from runtime.code.code_image import CodeImage, VariablePath
from runtime.code.compile_worker import compile_here
from runtime.code.intrinsics import Reference, SystemView
from runtime.code.native.tier import NativeTier
from runtime.code.user_program import UserProgram
from runtime.contract.artifact import Artifact, VarInfo
from runtime.contract.refusal import Refusal
from runtime.contract.values import is_reference_type


@dataclass(frozen=True)
class BoundVariable:
    """A variable path with what it belongs to: a user program, or the globals."""

    program: UserProgram | None  # None: a global
    path: VariablePath


@dataclass
class Instances:
    image: CodeImage
    programs: list[UserProgram]  # by priority, then Program ID
    globals: Any
    bound: list[BoundVariable]
    by_name: dict[str, BoundVariable]
    outputs: list[BoundVariable]  # the output points (located %Q variables)


def instantiate(
    artifact: Artifact,
    system: SystemView,
    compile_units: Callable[[list[tuple[str, str]]], list[CodeType]] = compile_here,
    native: NativeTier | None = None,
) -> Instances:
    """Fresh instances of everything: every variable at its initial value."""
    image = CodeImage(
        artifact, system, compile_units=compile_units, native=native, memory_image=True
    )
    return instances_of(image)


def instances_of(image: CodeImage) -> Instances:
    """The instances of a new image, or fresh ones of an image whose instances are done
    with once it is `renew`ed (`padt test`: each test starts from them)."""
    artifact = image.artifact
    configs = sorted(artifact.programs, key=lambda p: (p.priority, p.program_id))
    # a program needs its own view of the globals when another program could change them
    # during its program cycle, or when its cycle spans several CPU cycles
    private = len(configs) > 1 or any(c.max_duration_us for c in configs)
    programs = []
    for config in configs:
        instance = image.new_instance(config.pou)
        # `prog();` in ST reaches the user program of that POU (the first by priority), so
        # a program called from another one is the same instance the task runs
        image.register_program(config.pou, instance)
        view = image.new_globals() if private and image.globals is not None else image.globals
        programs.append(
            UserProgram(config, instance, image.variable_paths(config.name, config.pou), view)
        )
    for pou in artifact.pous:  # a PROGRAM that is no user program still has one instance
        if pou.kind == "PROGRAM":
            image.register_program(pou.name, image.new_instance(pou.name))
    bound = [
        *(BoundVariable(p, path) for p in programs for path in p.paths),
        *(BoundVariable(None, path) for path in image.global_paths()),
    ]
    return Instances(image, programs, image.globals, bound, index(bound), output_points(bound))


def name_reference_roots(image: CodeImage, programs: list[UserProgram]) -> None:
    """Tell the references of the generated code (`REF(x)`) the path of every instance
    that may hold the variable they refer to: the program instances, the globals, and the
    function block and structure instances below them, so that a reference reads as
    `Main.fb.count`. Arrays of instances are not walked: a reference into one reads as its
    path below the element. Only code that makes references needs them."""
    roots = image.reference_roots()
    roots.clear()
    if not image.makes_references:
        return
    for view in (image.globals, *(program.view for program in programs)):
        roots[id(view)] = ""
    for program in programs:
        roots[id(program.instance)] = program.name
    for program in programs:
        members = image.members(program.config.pou)
        _name_members(image, roots, program.instance, members, program.name)
    if image.globals is not None and image.artifact.globals is not None:
        _name_members(image, roots, image.globals, image.artifact.globals.variables, "")


def _name_members(
    image: CodeImage,
    roots: dict[int, str],
    instance: Any,
    members: tuple[VarInfo, ...],
    prefix: str,
) -> None:
    """Name the struct and function block instances below `instance` (declaration order,
    depth first; the first name of an instance met twice wins)."""
    for var in members:
        inner = image.members(var.type)
        if not inner:
            if prefix and is_reference_type(var.type):
                _name_initial_reference(instance, var, members, prefix)
            continue  # elementary, or an array: not walked
        held = getattr(instance, var.attr, None)
        if held is None or id(held) in roots:
            continue
        path = f"{prefix}.{var.name}" if prefix else var.name
        roots[id(held)] = path
        _name_members(image, roots, held, inner, path)


def _name_initial_reference(
    instance: Any, var: VarInfo, members: tuple[VarInfo, ...], prefix: str
) -> None:
    """A reference made with its instance (an initial value `REF(x)`, x a variable of
    that instance) was made before the instance had a name, and reads as `x`: it takes
    the whole path, `Main.fb.x`."""
    held = getattr(instance, var.attr, None)
    if type(held) is not Reference or held.root is not instance or len(held.steps) != 1:
        return
    target = next((m for m in members if m.attr == held.steps[0]), None)
    if target is not None and str(held) == target.name:
        setattr(instance, var.attr, Reference(f"{prefix}.{target.name}", instance, held.steps))


def index(bound: list[BoundVariable]) -> dict[str, BoundVariable]:
    """Variables by upper-case path (ST names are case-insensitive); the first wins."""
    by_name: dict[str, BoundVariable] = {}
    for variable in bound:
        by_name.setdefault(variable.path.path.upper(), variable)
    return by_name


def output_points(bound: list[BoundVariable]) -> list[BoundVariable]:
    """The located %Q variables: listed with the instances (for a reload on its worker
    thread), not by the cycle that first writes outputs."""
    return [b for b in bound if b.path.location and b.path.location.upper().startswith("%Q")]


def instantiated(
    artifact: Artifact, system: SystemView, native: NativeTier | None = None
) -> Instances:
    """`instantiate`, with a configuration whose code fails while it is set up refused as
    `bad_configuration` (the resource keeps what it runs)."""
    try:
        return instantiate(artifact, system, native=native)
    except Exception as exc:  # generated code of an artifact that is not sound
        raise Refusal(
            "bad_configuration", f"the configuration cannot be set up: {type(exc).__name__}: {exc}"
        ) from None
