"""Where a located variable is: in the inputs (%I), the outputs (%Q) or the memory (%M) of
the resource's process image. The grammar takes an address without the area letter, since
IEC 61131-3 Annex F writes one (`%B6`) where a structure member is laid out relative to
its structure; padt lays out no structure (E0716), so outside one such an address would
locate nothing: refused."""

from __future__ import annotations

from backend.compiler.codes import Code
from backend.compiler.infer import Scope
from backend.compiler.resolve import Variable


def check_location_area(scope: Scope, variable: Variable) -> None:
    location = variable.location
    if location is None or location[1:2].upper() in ("I", "Q", "M"):
        return
    named = f"'{variable.name}' AT {location}" if variable.name != location else location
    scope.report(
        variable.pos,
        Code.LOCATION_AREA,
        f"{named}: a location names its area, %I (input), %Q (output) or %M "
        f"(memory), as in %I{location[1:]}",
    )
