"""The PES: one process per resource, running compiled IEC 61131-3 code cyclically.

Nothing here imports the backend or the frontend: the compiled artifact
(`runtime.artifact`) is the only contract with the engineering side.
"""
