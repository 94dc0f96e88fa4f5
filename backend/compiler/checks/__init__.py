"""The rules of the check stage, one module per concern; `backend.compiler.check` runs them."""
