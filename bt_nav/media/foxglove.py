"""Foxglove's WebSocket protocol for ``bt-nav view --foxglove``: the live (or recorded) messages as ROS 2 CDR with
their ``ros2msg`` schemas, so Foxglove shows them with its own panels (LaserScan, Odometry, ...).

Why in media: it turns messages into a viewer's stream, as :mod:`bt_nav.media.view` does for the browser page;
the command (:mod:`bt_nav.cli.view`) only chooses and starts it. ``foxglove-sdk`` is imported when a bridge starts.
"""

from __future__ import annotations

import threading
from typing import Any

from bt_nav.media.bag import typestore


class FoxgloveBridge:
    """Forwards (topic, msgtype, t_ns, cdr) to a Foxglove WebSocket server, one channel per topic."""

    def __init__(self, host: str, port: int) -> None:
        import foxglove

        self._foxglove = foxglove
        self.server = foxglove.start_server(name="bt_nav", host=host, port=port)
        self.channels: dict[str, Any] = {}
        self.lock = threading.Lock()

    def feed(self, topic: str, msgtype: str, t_ns: int, data: bytes, _qos: Any = None) -> None:
        """One message (the GraphTap handler signature)."""
        with self.lock:
            channel = self.channels.get(topic)
            if channel is None:
                text, _ = typestore().generate_msgdef(msgtype)
                schema = self._foxglove.Schema(name=msgtype, encoding="ros2msg", data=text.encode())
                channel = self.channels[topic] = self._foxglove.Channel(topic, schema=schema, message_encoding="cdr")
        channel.log(data, log_time=int(t_ns))

    def close(self) -> None:
        """Stop the server."""
        self.server.stop()
