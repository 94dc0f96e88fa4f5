"""The runtime before everything else on the machine. A PES that shares its computer with
the PADT, browsers and builds must not see its cycle stretched by them: the runtime asks
the operating system for a higher priority (a lower nice value; it takes CAP_SYS_NICE,
which root and a container granted it have) before it starts any thread, so that every
thread of it has it: a thread of normal priority that holds the GIL and waits for a CPU
would hold up the cycle all the same. Without it the resource runs at normal priority and
says so in its log."""

from __future__ import annotations

import os
import threading

DEFAULT_NICE = -10
NICE_RANGE = range(-20, 20)


def raise_priority(nice: int) -> str:
    """Give the calling thread `nice` (Linux: per thread); what came of it, for the log."""
    if nice == 0:
        return "normal priority (nice 0)"
    try:
        os.setpriority(os.PRIO_PROCESS, threading.get_native_id(), nice)
    except OSError as exc:
        return f"normal priority: nice {nice} was refused ({exc.strerror}; needs CAP_SYS_NICE)"
    return f"nice {nice}"
