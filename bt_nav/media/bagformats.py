"""The one home of reading bag formats: rosbag2 MCAP (complete, or cut short: walked record by record with the
``mcap`` stream reader up to the cut), rosbag2 sqlite3 and ROS 1 bags (``rosbags``' readers, decoded with the bag's
own message definitions where the Jazzy types lack one), for every reader of bags: the simulator's
(:mod:`bt_nav.media.bagread`: ``bt-nav video``, ``replay``, ``view``) and a robot's (:mod:`bt_nav.media.robotbag`:
the check-off, a robot's film).

Two ways out: :func:`iter_messages` (topic, msgtype, t_ns, CDR bytes) of a rosbag2 bag, MCAP or sqlite3 (what the
Foxglove bridge forwards, what :func:`bt_nav.media.bagread.read_bag` decodes), and :func:`decoded_messages`
(topic, msgtype, t_ns, decoded message) of any format, ROS 1 too. Errors: :class:`bt_nav.media.bag.BagError`
naming the file. No rclpy.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

from bt_nav.media.bag import BagError

SETBOOL_EVENT = "std_srvs/srv/SetBool_Event"

#: std_srvs/SetBool's request, response and service event (rosbag2's service introspection), which rosbags lacks.
_SETBOOL_TYPES = {"std_srvs/srv/SetBool_Request": "bool data\n",
                  "std_srvs/srv/SetBool_Response": "bool success\nstring message\n",
                  SETBOOL_EVENT: "service_msgs/msg/ServiceEventInfo info\nstd_srvs/srv/SetBool_Request[<=1] request\n"
                                 "std_srvs/srv/SetBool_Response[<=1] response\n"}


def bag_path(path: Path) -> Path:
    """The bag a path names: a rosbag2 bag's .db3/.mcap file stands for its directory (which has metadata.yaml)."""
    if path.is_file() and path.suffix in (".db3", ".mcap") and (path.parent / "metadata.yaml").exists():
        return path.parent
    return path


def is_mcap_only(path: str | Path) -> bool:
    """True for what the MCAP path of :func:`iter_messages` takes best (an .mcap file, or a directory of them and
    no .db3); False for a sqlite3 rosbag2 bag or a ROS 1 .bag."""
    p = bag_path(Path(path))
    if p.is_file():
        return p.suffix not in (".bag", ".db3")
    return not any(p.glob("*.db3")) if p.is_dir() else True


def bag_files(path: str | Path) -> tuple[Path, list[Path]]:
    """(bag directory or file, its storage files: .mcap, or a sqlite3 bag's .db3, or the ROS 1 .bag itself);
    BagError naming ``path`` when there is none."""
    p = bag_path(Path(path))
    if p.is_file():
        return p, [p]
    if p.is_dir():
        files = sorted(p.glob("*.mcap")) or (sorted(p.glob("*.db3")) if (p / "metadata.yaml").is_file() else [])
        if files:
            return p, files
        raise BagError(f"{p}: no .mcap or .db3 file in this directory (not a rosbag2 bag)")
    raise BagError(f"{p}: no such bag (a rosbag2 directory, its .mcap or .db3 file, or a ROS 1 .bag)")


def _rosbags_messages(bag: Path) -> Iterator[tuple[str, str, int, bytes]]:
    """(topic, msgtype, t_ns, cdr) through the rosbags reader (complete bags only)."""
    from rosbags.rosbag2 import Reader

    with Reader(bag) as reader:
        for conn, t_ns, data in reader.messages():
            yield conn.topic, conn.msgtype, t_ns, bytes(data)


def _stream_messages(files: list[Path], status: dict[str, Any]) -> Iterator[tuple[str, str, int, bytes]]:
    """(topic, msgtype, t_ns, cdr) record by record with the ``mcap`` stream reader, stopping at a cut."""
    from mcap.exceptions import McapError
    from mcap.records import Channel, Message, Schema
    from mcap.stream_reader import StreamReader

    for file in files:
        schemas: dict[int, str] = {}
        channels: dict[int, tuple[str, str]] = {}
        with file.open("rb") as stream:
            try:
                for record in StreamReader(stream, skip_magic=False).records:
                    if isinstance(record, Schema):
                        schemas[record.id] = record.name
                    elif isinstance(record, Channel):
                        channels[record.id] = (record.topic, schemas.get(record.schema_id, ""))
                    elif isinstance(record, Message) and record.channel_id in channels:
                        topic, msgtype = channels[record.channel_id]
                        yield topic, msgtype, record.log_time, record.data
            except (McapError, EOFError, ValueError, OSError) as exc:
                status["truncated"] = True
                detail = str(exc) or "the file ends inside a record"
                status["reason"] = f"{file}: cut short or damaged ({type(exc).__name__}: {detail})"


def iter_messages(path: str | Path, status: dict[str, Any] | None = None) -> Iterator[tuple[str, str, int, bytes]]:
    """Every message of a bag as (topic, msgtype, t_ns, cdr), complete or cut short (see the module docstring).

    ``status`` (a dict) receives ``truncated`` and ``reason`` when the stream reader had to stop early.
    """
    from rosbags.rosbag2 import ReaderError

    bag, files = bag_files(path)
    status = status if status is not None else {}
    if bag.suffix == ".bag":
        raise BagError(f"{bag}: a ROS 1 bag holds no CDR payloads (read it with read_bag)")
    if bag.is_dir() and (bag / "metadata.yaml").is_file():
        try:
            yield from _rosbags_messages(bag)
            return
        except (ReaderError, OSError, ValueError, KeyError) as exc:
            status["reason"] = f"{bag}: {exc}"  # fall through: read what the file holds
    status.setdefault("truncated", True)  # no (usable) metadata: the writer did not finish
    yield from _stream_messages(files, status)


def robot_typestore() -> Any:
    """The Jazzy types plus std_srvs/SetBool's service event (rosbags has no service event types)."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    parsed: dict[str, Any] = {}
    for name, text in _SETBOOL_TYPES.items():
        parsed.update(get_types_from_msg(text, name))
    # the parser files a srv's types under std_srvs/srv/msg/; rosbag2 names them std_srvs/srv/SetBool_Event
    store.register({key.replace("/srv/msg/", "/srv/"): _renamed(value) for key, value in parsed.items()})
    return store


def _renamed(value: Any) -> Any:
    """A parsed type definition with ``std_srvs/srv/msg/`` references as ``std_srvs/srv/``."""
    if isinstance(value, str):
        return value.replace("/srv/msg/", "/srv/")
    if isinstance(value, tuple | list):
        return type(value)(_renamed(v) for v in value)
    return value


def decoded_messages(path: str | Path, wanted: set[str] | None = None,
                     notes: list[str] | None = None) -> Iterator[tuple[str, str, int, Any]]:
    """(topic, msgtype, receive ns, decoded message) of every topic in ``wanted`` (None: all) of a bag of any
    format, rosbag2 sqlite3 or MCAP or ROS 1; the bag's topic table first as ("", "", 0, {topic: type}). The one
    reader of those formats: the check-off, ``bt-nav video``, ``replay`` and ``view`` read sqlite3 and ROS 1 bags
    through it (:func:`bt_nav.media.bagread.read_bag`)."""
    yield from _decoded(Path(path), wanted, [] if notes is None else notes)


def bag_topics(path: str | Path) -> dict[str, str]:
    """{topic: type} of a bag of any format, without reading its messages (a cut-short MCAP is walked)."""
    for topic, _, _, types in _decoded(Path(path), set(), []):
        if not topic:
            return dict(types)
    return {}


def _decoded(path: Path, wanted: set[str] | None, notes: list[str]) -> Iterator[tuple[str, str, int, Any]]:
    """(topic, msgtype, receive ns, message) of the ``wanted`` topics (None: all), any bag format; the bag's topic
    table first as ("", "", 0, {topic: type})."""
    store = robot_typestore()
    path = bag_path(path)
    if path.is_file() and path.suffix == ".bag":
        from rosbags.rosbag1 import Reader as Reader1
        from rosbags.typesys import Stores, get_typestore

        reader, store, decode = Reader1(path), get_typestore(Stores.ROS1_NOETIC), "deserialize_ros1"
    elif path.is_dir() and (path / "metadata.yaml").exists():
        from rosbags.rosbag2 import Reader

        reader, decode = Reader(path), "deserialize_cdr"
    else:
        yield from _stream_decoded(path, wanted, store, notes)
        return
    try:
        reader.open()
    except Exception as exc:  # noqa: BLE001 - a cut MCAP (no summary) is still read record by record
        if not (path.is_dir() and any(path.glob("*.mcap"))):
            raise
        notes.append(f"the bag's index is unreadable ({type(exc).__name__}: {exc}): read record by record")
        yield from _stream_decoded(path, wanted, store, notes)
        return
    try:
        yield "", "", 0, {c.topic: c.msgtype for c in reader.connections}
        conns = [c for c in reader.connections if wanted is None or c.topic in wanted]
        if not conns:
            return  # (rosbags reads every connection when given none)
        if decode == "deserialize_ros1":
            _register_bag_types(store, conns)
        skipped = 0
        for conn, t_ns, raw in reader.messages(connections=conns):
            try:
                msg = getattr(store, decode)(bytes(raw), conn.msgtype)
            except Exception:  # noqa: BLE001 - a damaged payload or a type the store lacks: skip it
                skipped += 1
                continue
            yield conn.topic, conn.msgtype, t_ns, msg
        if skipped:
            notes.append(f"{skipped} messages could not be decoded and were skipped")
    finally:
        reader.close()


def _register_bag_types(store: Any, conns: list[Any]) -> None:
    """A ROS 1 bag's own message definitions (Noetic's store lacks tf2_msgs, for one): each connection's type
    registered from the definition text the bag carries, where the store does not have it."""
    from rosbags.typesys import get_types_from_msg

    for conn in conns:
        text = getattr(conn.msgdef, "data", "")
        if conn.msgtype in store.fielddefs or not text:
            continue
        try:
            store.register(get_types_from_msg(text, conn.msgtype))
        except Exception:  # noqa: BLE001 - a definition rosbags cannot parse: its messages are skipped, and counted
            continue


def _stream_decoded(path: Path, wanted: set[str] | None, store: Any,
                    notes: list[str]) -> Iterator[tuple[str, str, int, Any]]:
    """A cut-short rosbag2 MCAP (no metadata.yaml or no summary), record by record."""
    status: dict[str, Any] = {}
    types: dict[str, str] = {}
    rows = []
    for topic, msgtype, t_ns, data in iter_messages(path, status):
        types[topic] = msgtype
        if wanted is None or topic in wanted:
            rows.append((topic, msgtype, t_ns, data))
    if not types and status.get("reason"):
        raise BagError(f"nothing readable before the damage: {status['reason']}")
    yield "", "", 0, types
    for topic, msgtype, t_ns, data in rows:
        try:
            yield topic, msgtype, t_ns, store.deserialize_cdr(data, msgtype)
        except Exception:  # noqa: BLE001 - unknown type or damaged payload
            continue
    if status.get("reason"):
        notes.append(f"read up to where the bag is cut: {status['reason']}")
