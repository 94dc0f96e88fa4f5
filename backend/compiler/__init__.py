"""The IEC 61131-3 compiler, in named stages: parse -> resolve -> check -> generate -> CRC.

`compile_sources` in `pipeline` runs them all; each stage module can be used on its own.
"""
