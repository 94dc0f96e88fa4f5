"""The `padt` command: one entry point for the compiler, the runtime, the UI and the demo."""
