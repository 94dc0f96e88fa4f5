"""The process image: what the I/O delivered for the located inputs (`%I`), read at the
start of a CPU cycle, and the output image (`%Q`) as it goes to the field, which holds the
safe values in STOP and ERROR STOP (0 / FALSE, or as configured per output)."""

from __future__ import annotations

from typing import Any

from runtime.contract.artifact import Artifact
from runtime.variables import Variables


def default_value(type_name: str) -> Any:
    """The safe value of an output: 0 / FALSE / empty (de-energise to trip)."""
    name = type_name.upper()
    if name == "BOOL":
        return False
    if name in ("REAL", "LREAL"):
        return 0.0
    if name.startswith(("STRING", "WSTRING", "CHAR", "WCHAR")):
        return ""
    return 0


class ProcessImage:
    # slots: the CPU cycle in C reads them at their offsets (padt_cycle.c)
    __slots__ = (
        "_safe_values",
        "_variables",
        "delivered",
        "outputs",
    )

    def __init__(self, variables: Variables) -> None:
        self._variables = variables
        self.outputs: dict[str, Any] = {}  # the output image as last written to the field
        # what the I/O delivered since the last CPU cycle read it (the cycle tests it)
        self.delivered: dict[str, Any] = {}
        self._safe_values: dict[str, Any] = {}  # configured safe values by upper-case path

    def configure(self, artifact: Artifact) -> None:
        self._safe_values = {name.upper(): value for name, value in artifact.safe_values}

    def set_inputs(self, values: dict[str, Any]) -> None:
        """What the I/O delivered for located inputs; read at the next cycle's start."""
        self.delivered.update(values)

    def read_inputs(self) -> None:
        for path, value in sorted(self.delivered.items()):
            bound = self._variables.find(path)
            if bound is not None:
                self._variables.store(bound, value)
        self.delivered.clear()

    def write_outputs(self, safe: bool) -> None:
        """The output image (located %Q variables) as the I/O sends it to the field."""
        outputs = self._variables.outputs
        if not outputs and not self.outputs:  # none: the empty image stays (never changed)
            return
        image: dict[str, Any] = {}
        for bound in outputs:
            if safe:
                configured = self._safe_values.get(bound.path.path.upper())
                image[bound.path.path] = (
                    configured if configured is not None else default_value(bound.path.type)
                )
            else:
                image[bound.path.path] = self._variables.read(bound)
        self.outputs = image
