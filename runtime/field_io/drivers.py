"""The field I/O drivers a resource knows: the one place a driver is registered."""

from __future__ import annotations

from runtime.field_io.driver import DriverKind
from runtime.field_io.modbus.driver import ModbusOptions, modbus_kind
from runtime.field_io.opcua.kind import OpcuaOptions, opcua_kind
from runtime.field_io.peer_exchange.kind import ExchangeOptions, exchange_kind


def driver_kinds(
    modbus: ModbusOptions, opcua: OpcuaOptions, exchange: ExchangeOptions
) -> tuple[DriverKind, ...]:
    """Every driver, in the order they exchange with the cycle; each with the options the
    runtime gave it."""
    return (modbus_kind(modbus), opcua_kind(opcua), exchange_kind(exchange))
