"""The PES: one process per resource, running compiled IEC 61131-3 code cyclically.

Nothing here imports the backend, the frontend or the command line. `runtime.contract` is
what the engineering side may know of it: the compiled artifact and the bus protocol.
"""
