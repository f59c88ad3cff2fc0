"""Foxglove: the launch live over the Foxglove WebSocket protocol (`--foxglove`), served by the
foxglove-sdk package. Imported only when asked for."""

#: the port Foxglove's "Foxglove WebSocket" connection offers by default
DEFAULT_PORT = 8765
