"""What a driver of a server and remote devices does the same whatever its protocol: the
server starts before the devices connect and stops after they are done; the inputs of
lost devices are the driver's `bad`; both are bound anew together."""

from __future__ import annotations

from typing import Protocol

from runtime.field_io.remote_devices import RemoteDevices


class Startable(Protocol):
    async def start(self) -> None: ...
    async def stop(self) -> None: ...


class ServerAndDevices:
    def __init__(self, server: Startable | None, devices: RemoteDevices) -> None:
        self._serving = server
        self._devices = devices

    @property
    def bad(self) -> frozenset[str]:
        """The upper-case paths of inputs of lost devices."""
        return self._devices.bad

    # ---- the I/O thread
    async def start(self) -> None:
        if self._serving is not None:
            await self._serving.start()
        self._devices.start()

    async def stop(self) -> None:
        await self._devices.stop()
        if self._serving is not None:
            await self._serving.stop()

    # ---- the cycle thread
    def rebind(self) -> None:
        self._devices.rebind()
        if self._serving is not None:
            self._rebind_server()

    def _rebind_server(self) -> None:
        """The server's side of `rebind` (there is a server)."""
