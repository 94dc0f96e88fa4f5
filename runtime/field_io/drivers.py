"""The field I/O drivers a resource knows: the one place a driver is registered."""

from __future__ import annotations

from runtime.field_io.driver import DriverKind
from runtime.field_io.modbus.driver import ModbusOptions, modbus_kind
from runtime.field_io.opcua.kind import OpcuaOptions, opcua_kind


def driver_kinds(modbus: ModbusOptions, opcua: OpcuaOptions) -> tuple[DriverKind, ...]:
    """Every driver, in the order they exchange with the cycle; each with the options the
    runtime's command line gave it."""
    return (modbus_kind(modbus), opcua_kind(opcua))
