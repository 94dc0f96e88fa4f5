"""Modbus TCP as a field I/O driver: the served process image (`image_server.py`, metered
by `request_meter.py`) and the remote devices the resource polls (`poller.py`), driven by
`driver.py` (docs/modbus.md)."""
