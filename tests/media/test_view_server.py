"""The view server (bag playback): state over HTTP and SSE, and no way for a client to break it."""

from __future__ import annotations

import http.client
import json
import socket
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from bt_nav.media.bagread import read_bag
from bt_nav.media.video import world_of
from bt_nav.media.view import BagScene, ViewServer


@pytest.fixture
def server(mission_bag: Path) -> Iterator[ViewServer]:
    rec = read_bag(mission_bag)
    srv = ViewServer(BagScene(rec, world_of(rec)), "127.0.0.1", 0)
    srv.start()
    yield srv
    srv.close()


def request(srv: ViewServer, method: str, path: str, body: bytes | None = None) -> tuple[int, bytes]:
    conn = http.client.HTTPConnection(*srv.server_address[:2], timeout=5)
    try:
        conn.request(method, path, body=body, headers={"Content-Type": "application/json"} if body else {})
        response = conn.getresponse()
        return response.status, response.read()
    finally:
        conn.close()


def test_binds_loopback_and_serves_page_world_state(server: ViewServer) -> None:
    assert server.server_address[0] == "127.0.0.1"
    status, page = request(server, "GET", "/")
    assert status == 200 and b"EventSource" in page
    world = json.loads(request(server, "GET", "/world")[1])
    assert world["name"] == "stage_4" and world["segments"] and world["mode"] == "bag"


def test_seek_moves_the_robot_and_the_tree(server: ViewServer) -> None:
    assert request(server, "POST", "/control", b'{"t": 2}')[0] == 200
    early = json.loads(request(server, "GET", "/state")[1])
    assert request(server, "POST", "/control", b'{"t": 11.5}')[0] == 200
    late = json.loads(request(server, "GET", "/state")[1])
    assert early["pose"] != late["pose"] and len(late["trail"]) > len(early["trail"])
    assert any(row["active"] for row in late["tree"]) and late["tree"][0]["name"].startswith("Mission")
    assert len(late["events"]) > len(early["events"]) and late["scan"]


@pytest.mark.parametrize("body", [b"garbage", b"[1, 2]", b'{"t": "soon"}', b'{"t": NaN}', b'{"play": 3}',
                                  b'{"speed": -1}', b'{"unknown": 1}', b"{}", b'{"t": 1e999}', b"\xff\xfe"])
def test_malformed_control_gets_400_and_the_server_lives(server: ViewServer, body: bytes) -> None:
    status, reply = request(server, "POST", "/control", body)
    assert status == 400 and "error" in json.loads(reply)
    assert request(server, "GET", "/state")[0] == 200


def test_garbage_requests_and_vanishing_clients(server: ViewServer) -> None:
    host, port = server.server_address[:2]
    for junk in (b"GARBAGE\r\n\r\n", b"\x00\x01\x02" * 100 + b"\r\n\r\n", b"GET /" + b"a" * 70000 + b" HTTP/1.1\r\n",
                 b"POST /control HTTP/1.1\r\nContent-Length: 99999999\r\n\r\n{"):
        with socket.create_connection((host, port), timeout=5) as sock:
            sock.sendall(junk)
            sock.settimeout(2)
            try:
                sock.recv(1024)
            except (TimeoutError, ConnectionResetError):
                pass
    for _ in range(5):  # clients that open the stream and vanish mid-stream
        sock = socket.create_connection((host, port), timeout=5)
        sock.sendall(b"GET /stream HTTP/1.1\r\nHost: x\r\n\r\n")
        assert b"text/event-stream" in sock.recv(4096)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, b"\x01\x00\x00\x00\x00\x00\x00\x00")  # RST on close
        sock.close()
    request(server, "POST", "/control", b'{"play": true, "speed": 50}')  # make the stream write to them
    time.sleep(1.5)
    assert request(server, "GET", "/state")[0] == 200
    assert request(server, "GET", "/nowhere")[0] == 404


def test_stream_sends_states(server: ViewServer) -> None:
    host, port = server.server_address[:2]
    with socket.create_connection((host, port), timeout=5) as sock:
        sock.sendall(b"GET /stream HTTP/1.1\r\nHost: x\r\n\r\n")
        data = b""
        deadline = time.monotonic() + 5
        while b"\ndata: " not in data and time.monotonic() < deadline:
            data += sock.recv(65536)
    payload = data.split(b"\ndata: ", 1)[1].split(b"\n\n", 1)[0]
    assert json.loads(payload)["mode"] == "bag"


def test_people_walking_are_in_the_state_and_the_lab_has_no_circle(tmp_path: Path) -> None:
    from bt_nav.media.bag import MissionBag
    from bt_nav.run.lockstep import run_mission

    with MissionBag(tmp_path / "bag", mission={"world": "lab_passerby", "profile": "lab"}) as bag:
        run_mission("lab_passerby", "A", 0, profile="lab", duration=3.0, sink=bag)
    rec = read_bag(tmp_path / "bag")
    scene = BagScene(rec, world_of(rec))
    try:
        scene.control({"t": 2.0})
        state = scene.state()
        assert len(state["walkers"]) == 3 and all(len(c) == 3 for c in state["walkers"])
        assert state["circle"] is False
    finally:
        scene.close()
