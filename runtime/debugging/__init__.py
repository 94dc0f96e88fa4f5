"""Debugging in the code (docs/debugging.md): breakpoints and logpoints at ST statements,
a program stopped mid-cycle in BKPT while the others run on, stepping, the call stack and
the variables of its frames.

A program that a breakpoint may stop runs its program cycle in a greenlet of its own (as a
time-sliced program does, runtime/slicing.py), with a Python line tracer installed only
while that greenlet runs; the tracer maps each generated line to its ST statement through
the artifact's line table and switches back to the CPU cycle to stop. Nothing else of the
resource is traced, and with nothing armed nothing is traced at all.
"""
