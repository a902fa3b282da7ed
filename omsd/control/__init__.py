"""The control API: reach behind a running daemon's boards (switches, inputs, slip, faults,
time, power) and watch them, over a local socket. :mod:`omsd.control.server` is the daemon's
side, :mod:`omsd.control.client` the typed Python client that ``omsd ctl`` and the pytest
plugin use, :mod:`omsd.control.protocol` the wire format they share."""
