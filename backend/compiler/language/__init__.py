"""The language services: what an editor asks of the compiler while one types (diagnostics,
completion, hover, definition, references, rename, outline), one module per service over
one `Analysis` of the project. The browser's editor, the REST API and `padt lsp` are
adapters over these functions."""
