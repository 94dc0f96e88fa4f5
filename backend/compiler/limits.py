"""The compiler's limits, each reported as an error with its own code (docs/language.md,
"Limits", gives the figures; docs/diagnostics.md the codes).

They are chosen so that compiling any input stays within about 1 GB of memory and 10 s,
and that what compiles can be loaded and run by a resource, while real programs (OSCAT, the
IEC and rusty test corpora) stay far below them.
"""

from __future__ import annotations

MiB = 1 << 20

# Source: compile time grows with the tokens (the parse about 30 µs each, up to 50 on our
# build machines: 200,000 once took 10.5 s there); comments and white space cost only
# their bytes.
MAX_FILE_BYTES = 4 * MiB
MAX_PROJECT_BYTES = 16 * MiB
MAX_PROJECT_FILES = 2_000
MAX_PROJECT_TOKENS = 150_000

# Nesting, so that a resource can load the generated code: CPython allows 200 levels of
# parentheses and 99 of indentation, and one ST level can cost up to three of the first and
# two of the second (the generator refuses deeper indentation itself: an ELSIF whose
# condition calls a function with outputs nests its branch); 20 nested loops; and its
# compiler recurses once per `elif`, up to three times the recursion limit (a resource
# keeps Python's 1,000).
MAX_STATEMENT_DEPTH = 40
MAX_LOOP_DEPTH = 20
MAX_BRANCH_DEPTH = 1_000
MAX_INDENT = 99
MAX_EXPRESSION_DEPTH = 60
# Arrays of arrays, structures and function blocks holding others: generated code nests as
# deep, and so do copying and instantiating in a resource.
MAX_DATA_DEPTH = 32
# Values of data (checks/data.py counts them): a resource gives each up to about 600 bytes
# (an elementary value inside a structure or block has a path of its own for online values).
MAX_ARRAY_VALUES = 1_000_000
MAX_DATA_VALUES = 1_000_000

# Generated code: a resource's Python compiles a unit in up to about 150 bytes per character
# (a long list of initial values), so a unit's Python stays within 2 MiB; the typed forms the
# artifact carries (about 2.7 times the Python, 4 times for lists of constants) within
# 48 MiB, so that the artifact, whose JSON escapes their quotes (a fifth more), stays within
# the 64 MiB a runtime takes. Repeated initial values (`[100000(1.5)]`) and transitions
# sharing a step grow both.
MAX_UNIT_CODE = 2 * MiB
MAX_PROJECT_FORM = 48 * MiB

# `(* (* *) *)`: how deep comments nest (a regular expression reads them, and cannot count);
# a comment nested deeper is read as IEC 61131-3 edition 2 reads it, up to its first `*)`.
MAX_COMMENT_NESTING = 8

# Literals, as written between their quotes or as their characters.
MAX_STRING_LITERAL = 65_535
MAX_NUMBER_LITERAL = 1_000
