"""The browser view: a standard-library HTTP server with server-sent events, and the state it shows.

Sources of state, one format (:meth:`Scene.state`):

- :class:`LiveScene`: fed message by message (topic, msgtype, sim-time ns, CDR) by the ``bt-nav view``
  command's :class:`bt_nav.ros.graphtap.GraphTap`; decoded with rosbags' typestore like a bag;
- :class:`BagScene`: a recorded :class:`~bt_nav.media.bagread.MissionRecord` played back; the page's
  slider and play button post ``{"t": seconds}`` / ``{"play": bool}`` to ``/control``.

Endpoints: ``/`` the page, ``/world`` the walls (JSON), ``/state`` the current state (JSON),
``/stream`` server-sent events (one state per change, at most 10 per second), ``POST /control``.
Robustness: any malformed request gets a 400 and a JSON reason, never a dead server; a client that
vanishes mid-stream ends only its own handler thread. The server binds 127.0.0.1 unless told otherwise.
No rclpy here.
"""

from __future__ import annotations

import json
import threading
import time
from collections import deque
from http import HTTPStatus
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any
from urllib.parse import parse_qs, urlsplit

import numpy as np
from bt_nav_sim.walkers import read_walkers_message

from bt_nav.media.bag import CMD, EVENTS, MISSION, ODOM, SCAN, TREE, TRUTH, WALKERS, typestore
from bt_nav.media.bagread import MissionRecord
from bt_nav.media.page import PAGE
from bt_nav.media.plot import start_circle
from bt_nav.mission.geometry import yaw_from_quaternion
from bt_nav.mission.snapshot import read_snapshot, snapshot_nodes

MAX_BODY = 4096  # bytes a /control request may carry
TRAIL_STEP = 0.02  # m between two kept trail points
EVENT_LINES = 12


def tree_json(snapshot: dict[str, Any] | None) -> list[dict[str, Any]]:
    """The rows of a ``~/tree`` snapshot (:mod:`bt_nav.mission.snapshot`) for the page, the running path flagged
    ``active`` (no rows for anything that is not a snapshot)."""
    if not snapshot:
        return []
    on_path = set(snapshot.get("path", ()))
    return [{"depth": r.depth, "name": r.name, "status": r.status, "feedback": r.feedback, "active": i in on_path}
            for i, r in enumerate(snapshot_nodes(snapshot))]


def world_json(world: Any) -> dict[str, Any]:
    """Walls, cylinders and bounds of a :class:`bt_nav_sim.world.World` (empty when None)."""
    if world is None:
        return {"name": "", "segments": [], "circles": [], "bounds": [-3, -3, 3, 3]}
    return {"name": world.name, "segments": np.round(world.segments, 4).tolist(),
            "circles": np.round(world.circles, 4).tolist(), "bounds": [float(b) for b in world.bounds]}


def scan_points(x: float, y: float, yaw: float, angles: np.ndarray, ranges: np.ndarray, range_max: float) -> list:
    """Scan returns in the world frame, [[x, y], ...] (rounded to mm; misses dropped)."""
    ok = np.isfinite(ranges) & (ranges < range_max)
    a = angles[ok] + yaw
    return np.round(np.column_stack([x + ranges[ok] * np.cos(a), y + ranges[ok] * np.sin(a)]), 3).tolist()


class Scene:
    """What the page shows; subclasses fill :meth:`state`. ``version`` rises on every change."""

    def __init__(self, world: Any = None, mode: str = "live") -> None:
        self.world = world
        self.mode = mode
        self.changed = threading.Condition()
        self.version = 0

    def bump(self) -> None:
        """Tell streaming clients that the state changed."""
        with self.changed:
            self.version += 1
            self.changed.notify_all()

    def state(self) -> dict[str, Any]:  # pragma: no cover - abstract
        """The current state (JSON-able)."""
        raise NotImplementedError

    def control(self, message: dict[str, Any]) -> dict[str, Any]:
        """Apply a client's control message; ValueError for one that makes no sense here."""
        raise ValueError("this view takes no control messages (live)")


class LiveScene(Scene):
    """State of a live graph, updated from raw messages (thread-safe)."""

    def __init__(self, world: Any = None) -> None:
        super().__init__(world, "live")
        self.ts = typestore()
        self.lock = threading.Lock()
        self.t = 0.0
        self.pose: tuple[float, float, float] | None = None
        self.have_truth = False
        self.trail: list[list[float]] = []
        self.scan: tuple[np.ndarray, np.ndarray, float] | None = None
        self.tree: list[dict[str, Any]] = []
        self.events: deque[str] = deque(maxlen=EVENT_LINES)
        self.cmd = (0.0, 0.0)
        self.walkers: list[list[float]] = []
        self.mission: dict[str, Any] = {}
        self.world_loader: Any = None  # callable(mission dict) -> World or None, set by the command

    def feed(self, topic: str, msgtype: str, t_ns: int, data: bytes, _qos: Any = None) -> None:
        """One message from the graph (the GraphTap handler signature)."""
        if topic not in (TRUTH, ODOM, SCAN, TREE, EVENTS, CMD, MISSION, WALKERS):
            return
        msg = self.ts.deserialize_cdr(data, msgtype)
        with self.lock:
            self.t = max(self.t, t_ns * 1e-9)
            self._apply(topic, msg)
        self.bump()

    def _apply(self, topic: str, msg: Any) -> None:
        if topic in (TRUTH, ODOM):
            if topic == ODOM and self.have_truth:
                return
            self.have_truth |= topic == TRUTH
            p, q = msg.pose.pose.position, msg.pose.pose.orientation
            self.pose = (p.x, p.y, yaw_from_quaternion(q.x, q.y, q.z, q.w))
            if not self.trail or np.hypot(p.x - self.trail[-1][0], p.y - self.trail[-1][1]) >= TRAIL_STEP:
                self.trail.append([round(p.x, 3), round(p.y, 3)])
        elif topic == SCAN:
            angles = msg.angle_min + msg.angle_increment * np.arange(len(msg.ranges))
            self.scan = (angles, np.asarray(msg.ranges, dtype=np.float32), float(msg.range_max))
        elif topic == TREE:
            self.tree = tree_json(read_snapshot(msg.data))
        elif topic == EVENTS:
            self.events.append(f"[{self.t:7.2f}] {msg.data}")
        elif topic == CMD:
            self.cmd = (msg.linear.x, msg.angular.z)
        elif topic == WALKERS:
            self.walkers = read_walkers_message(msg.data)[1].tolist()
        elif topic == MISSION:
            self.mission.update(json.loads(msg.data) if msg.data.startswith("{") else {})
            if self.world_loader is not None and self.world is None:
                self.world = self.world_loader(self.mission)

    def state(self) -> dict[str, Any]:
        with self.lock:
            pts = scan_points(*self.pose, *self.scan) if self.pose and self.scan else []
            return {"mode": "live", "t": round(self.t, 3), "pose": list(self.pose) if self.pose else None,
                    "trail": list(self.trail), "scan": pts, "tree": self.tree, "events": list(self.events),
                    "cmd": list(self.cmd), "walkers": self.walkers,
                    "circle": start_circle(self.mission.get("profile")) is not None, "version": self.version}


class BagScene(Scene):
    """Playback of a recorded mission: a playhead the page moves (slider) or lets run (play)."""

    def __init__(self, record: MissionRecord, world: Any = None) -> None:
        super().__init__(world, "bag")
        self.rec = record
        self.t = record.start
        self.playing = False
        self.speed = 1.0
        self._stop = threading.Event()
        threading.Thread(target=self._run, name="bag-playback", daemon=True).start()

    def _run(self) -> None:
        last = time.monotonic()
        while not self._stop.wait(0.1):
            now = time.monotonic()
            if self.playing:
                self.t = min(self.rec.end, self.t + (now - last) * self.speed)
                self.playing = self.t < self.rec.end
                self.bump()
            last = now

    def close(self) -> None:
        """Stop the playback thread."""
        self._stop.set()

    def control(self, message: dict[str, Any]) -> dict[str, Any]:
        """``{"t": s}`` seeks, ``{"play": bool}`` starts/stops, ``{"speed": x}`` sets the rate."""
        if not message or not set(message) <= {"t", "play", "speed"}:
            raise ValueError("expected an object with t, play and/or speed")
        if "t" in message:
            t = float(message["t"])
            if not np.isfinite(t):
                raise ValueError("t must be a finite number")
            self.t = min(max(t, self.rec.start), self.rec.end)
        if "play" in message:
            if not isinstance(message["play"], bool):
                raise ValueError("play must be true or false")
            self.playing = message["play"]
        if "speed" in message:
            speed = float(message["speed"])
            if not 0 < speed <= 100:
                raise ValueError("speed must be in (0, 100]")
            self.speed = speed
        self.bump()
        return {"t": self.t, "playing": self.playing}

    def state(self) -> dict[str, Any]:
        rec, t = self.rec, self.t
        tr = rec.truth
        i = int(np.searchsorted(tr.t, t, side="right")) - 1
        pose = [float(tr.x[i]), float(tr.y[i]), float(tr.yaw[i])] if i >= 0 else None
        scan = rec.scan_at(t)  # placed from the pose at the scan's own stamp
        pts = np.round(np.column_stack(scan[1:]), 3).tolist() if scan is not None else []
        step = max(1, (i + 1) // 1500)
        trail = np.round(np.column_stack([tr.x[: i + 1 : step], tr.y[: i + 1 : step]]), 3).tolist() if i >= 0 else []
        j = next((n for n in range(len(rec.trees) - 1, -1, -1) if rec.trees[n][0] <= t), -1)
        events = [f"[{et:7.2f}] {text}" for et, text in rec.events if et <= t][-EVENT_LINES:]
        c = int(np.searchsorted(rec.cmd[:, 0], t, side="right")) - 1 if len(rec.cmd) else -1
        walkers = rec.walkers_at(t)
        return {"mode": "bag", "t": round(t, 3), "start": rec.start, "end": rec.end, "playing": self.playing,
                "pose": pose, "trail": trail, "scan": pts, "tree": tree_json(rec.trees[j][1]) if j >= 0 else [],
                "events": events, "cmd": rec.cmd[c, 1:].tolist() if c >= 0 else [0.0, 0.0],
                "walkers": [] if walkers is None else walkers.tolist(),
                "circle": start_circle(rec.mission.get("profile")) is not None,
                "version": self.version}


def page_html() -> bytes:
    """The single page (:mod:`bt_nav.media.page`)."""
    return PAGE.encode()


class _Handler(BaseHTTPRequestHandler):
    server: ViewServer
    protocol_version = "HTTP/1.1"

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - quiet: one line per request is noise
        pass

    def _send(self, status: int, body: bytes, ctype: str = "application/json") -> None:
        self.send_response(status)
        self.send_header("Content-Type", ctype)
        self.send_header("Content-Length", str(len(body)))
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.wfile.write(body)

    def _json(self, status: int, value: Any) -> None:
        self._send(status, json.dumps(value).encode())

    def do_GET(self) -> None:  # noqa: D102
        path = urlsplit(self.path).path
        scene = self.server.scene
        if path in ("/", "/index.html"):
            self._send(HTTPStatus.OK, page_html(), "text/html; charset=utf-8")
        elif path == "/world":
            self._json(HTTPStatus.OK, {**world_json(scene.world), "mode": scene.mode})
        elif path == "/state":
            self._json(HTTPStatus.OK, scene.state())
        elif path == "/stream":
            self._stream(parse_qs(urlsplit(self.path).query))
        else:
            self._json(HTTPStatus.NOT_FOUND, {"error": f"no such page: {path[:80]}"})

    def do_POST(self) -> None:  # noqa: D102
        if urlsplit(self.path).path != "/control":
            self._json(HTTPStatus.NOT_FOUND, {"error": "POST only to /control"})
            return
        try:
            length = int(self.headers.get("Content-Length") or "0")
            if not 0 < length <= MAX_BODY:
                raise ValueError(f"body must be 1..{MAX_BODY} bytes")
            message = json.loads(self.rfile.read(length))
            if not isinstance(message, dict):
                raise ValueError("expected a JSON object")
            reply = self.server.scene.control(message)
        except (ValueError, TypeError, OverflowError) as exc:
            self.close_connection = True
            self._json(HTTPStatus.BAD_REQUEST, {"error": str(exc)[:200]})
            return
        self._json(HTTPStatus.OK, reply)

    def _stream(self, _query: dict[str, list[str]]) -> None:
        """Server-sent events until the client goes away or the server stops."""
        scene = self.server.scene
        self.send_response(HTTPStatus.OK)
        self.send_header("Content-Type", "text/event-stream")
        self.send_header("Cache-Control", "no-store")
        self.end_headers()
        self.close_connection = True
        seen = -1
        try:
            while not self.server.stopping.is_set():
                with scene.changed:
                    if scene.version == seen:
                        scene.changed.wait(timeout=1.0)
                if scene.version == seen:
                    self.wfile.write(b": keep-alive\n\n")  # finds a vanished client within a second
                else:
                    seen = scene.version
                    self.wfile.write(b"data: " + json.dumps(scene.state()).encode() + b"\n\n")
                self.wfile.flush()
                time.sleep(0.1)  # at most 10 states a second per client
        except (BrokenPipeError, ConnectionResetError, ConnectionAbortedError, TimeoutError):
            return  # the client went away: only this thread ends


class ViewServer(ThreadingHTTPServer):
    """The HTTP server of one scene; ``serve_forever`` in a thread, ``close()`` to stop."""

    daemon_threads = True
    request_queue_size = 32

    def __init__(self, scene: Scene, host: str = "127.0.0.1", port: int = 8000) -> None:
        self.scene = scene
        self.stopping = threading.Event()
        super().__init__((host, port), _Handler)

    def handle_error(self, request: Any, client_address: Any) -> None:
        """A request that broke its handler (a garbage line, a reset) is dropped quietly; the server goes on."""

    @property
    def url(self) -> str:
        """http://host:port/"""
        host, port = self.server_address[:2]
        return f"http://{host}:{port}/"

    def start(self) -> threading.Thread:
        """Serve in a daemon thread."""
        thread = threading.Thread(target=self.serve_forever, kwargs={"poll_interval": 0.2}, daemon=True)
        thread.start()
        return thread

    def close(self) -> None:
        """Stop serving and wake streaming clients."""
        self.stopping.set()
        self.scene.bump()
        self.shutdown()
        self.server_close()
        if isinstance(self.scene, BagScene):
            self.scene.close()
