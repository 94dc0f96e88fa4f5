"""The units of the typed form: what one POU, structure or the globals becomes, around the
statements of its bodies (statements.py) and the expressions in them (typed_form.py).

A PROGRAM or FUNCTION_BLOCK is a class: its slots with their initial values, the keys its
instances conform to, and its functions (the body, the chart's actions, the methods and
property accessors, or those it takes from the block that declares them). A FUNCTION is a
function. A structure and the globals are classes of slots alone; the SFC step structure
is the runtime's own class under the structure's name.
"""

from __future__ import annotations

from dataclasses import dataclass

from runtime.contract.code.statements import Stmt
from runtime.contract.code.typed_form import Expr


@dataclass(frozen=True, slots=True)
class Slot:
    """A variable of a class's instances, and the value each new instance starts with."""

    name: str
    initial: Expr


@dataclass(frozen=True, slots=True)
class Param:
    """A parameter of a function, and its value when a call does not pass it."""

    name: str
    default: Expr


@dataclass(frozen=True, slots=True)
class Function:
    """A FUNCTION, or (`method`) a function of a class whose instance comes first (`s`): a
    block's body (`__call__`), an action, a method, a property's accessor."""

    name: str
    params: tuple[Param, ...]
    body: tuple[Stmt, ...]
    method: bool = False


@dataclass(frozen=True, slots=True)
class Inherited:
    """A method a class takes as it is from the class `owner` of the block that declares it
    (the artifact lists, and the runtime makes, that class first)."""

    name: str
    owner: str


@dataclass(frozen=True, slots=True)
class Class:
    """A class: its slots (in the order they are initialised), the keys its instances
    conform to (for `?=`; none for a plain block or data), its functions."""

    name: str
    slots: tuple[Slot, ...]
    kinds: tuple[str, ...] = ()
    functions: tuple[Function | Inherited, ...] = ()


@dataclass(frozen=True, slots=True)
class Alias:
    """A name for an object of the runtime's (the SFC step structure is `_SfcStep`)."""

    name: str
    target: str


Unit = Class | Function | Alias
