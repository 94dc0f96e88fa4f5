"""The PADT's access levels (spec section 13), lowest first; each includes the ones before.
A module of its own, so that the command line can offer them without loading the API."""

PADT_LEVELS = ("read-only", "read-write", "security-administrator")
ADMINISTRATOR = PADT_LEVELS[-1]
