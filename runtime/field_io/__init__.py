"""Field I/O: the exchange between the CPU cycle and the field I/O drivers (`exchange.py`),
the interface every driver implements (`driver.py`), the drivers a resource knows
(`drivers.py`) and the one thread they all run on (`io_thread.py`). Modbus TCP is in
`modbus/`. docs/field-io.md tells how to add a driver."""

from runtime.field_io.exchange import FieldIo

__all__ = ["FieldIo"]
