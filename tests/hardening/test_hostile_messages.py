"""/ws/link and every channel, hit with the messages an attacker sends: `type` as a list, an object, a number or
null, numbers in superscript digits or thousands of digits, lone surrogates and NUL, nested and oversized JSON,
hostile channel paths. Each message gets an error naming its field (a relay channel, which takes nothing, drops
it); the link and every other channel stay open and keep working. One live lab (a real skill server) serves the
module; the hypothesis pass draws more of the same on one link."""

from __future__ import annotations

import json
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from tests.conftest import STUDENT_PASSWORD, LabClient, LiveServer, _let_go, add_test_account, make_test_app

LINK_ERROR_FIELDS = {"message", "type", "sub", "path"}
# The control messages of /ws/link, each wrong in one way (the JSON text as sent).
HOSTILE_CONTROL = (
    '{"type": ["subscribe"], "sub": 1, "path": "/ws/robots/lab-1/telemetry"}',
    '{"type": {"subscribe": true}, "sub": 1}',
    '{"type": 1}', '{"type": null}', '{"type": 1e999}', '{"type": "\\ud800"}', '{"type": "sub\\u0000scribe"}',
    "null", "[]", '"subscribe"', "7.5", "{", "²", "² {}", "¹²³ hello", "0 {}", "1" * 30 + " {}",
    '{"type": "subscribe", "sub": "²", "path": "/ws/robots/lab-1/telemetry"}',
    '{"type": "subscribe", "sub": ' + "9" * 4000 + ', "path": "/ws/x"}',
    '{"type": "subscribe", "sub": 1e999, "path": "/ws/x"}',
    '{"type": "subscribe", "sub": [1], "path": "/ws/x"}',
    '{"type": "subscribe", "sub": 1, "path": ["/ws/robots/lab-1/telemetry"]}',
    '{"type": "subscribe", "sub": 1, "path": "/ws/robots/\\ud800/chat"}',
    '{"type": "subscribe", "sub": 1, "path": "/ws/robots/lab-1\\u0000/chat"}',
    '{"\\udfff": 1, "type": "subscribe"}',
    '{"type": "unsubscribe", "sub": {"sub": 1}}',
    "[" * 2000 + "]" * 2000,
    '{"type": "subscribe", "path": ' + "[" * 100 + "]" * 100 + "}",
)
# Channel paths an attacker subscribes to: each closes its own sub (4404, 4403 or 1013), never the link.
HOSTILE_PATHS = (
    "/ws/robots/%00/chat", "/ws/robots/%ED%A0%80/drive", "/ws/robots/lab-1%00/queue", "/ws/robots/²/camera",
    "/ws/robots/" + "x" * 200 + "/telemetry", "/ws/robots/lab-1/goals/%00", "/ws/robots/lab-1/goals/%C2%B2",
    "/ws/robots/lab-1/goals/" + "g" * 150, "/ws/tour-sessions/²", "/ws/tour-sessions/%00",
    "/ws/tour-sessions/99999999999999999999999", "/ws/tour-sessions/2147483648", "/ws/tour-sessions/-1",
    "/ws/practice/camera", "/ws/practice/camera%00", "/ws/link", "/ws/../ws/link", "/ws/%2e%2e/api/practice",
    "/ws/courses/²/class-wall", "/ws/courses/2147483648/class-wall", "/ws/courses/1/class-wall/chat",
    "/ws/class-session/wall", "/ws/class-session/chat",
)
# A channel's messages, each wrong in one way (sent as "<sub> <text>").
HOSTILE_CHANNEL = (
    '{"type": ["drive"], "sequence": 1, "linear_mps": 0, "angular_radps": 0}',
    '{"type": {"say": 1}, "body": "hi"}', '{"type": ["join"]}', '{"type": 3}', '{"type": null}', "null", "[]",
    '"²"', "²", "{", '{"type": "say", "body": "\\ud800"}', '{"type": "say", "body": "a\\u0000b"}',
    '{"type": "drive", "sequence": "²", "linear_mps": 0, "angular_radps": 0}',
    '{"type": "drive", "sequence": 1e999, "linear_mps": 0, "angular_radps": 0}',
    '{"type": "delete", "id": ' + "9" * 900 + "}", '{"type": "ping", "id": "²"}', '{"\\ud800": "drive"}',
    "[" * 1400 + "]" * 1400, '{"type": "say", "body": "' + "x" * 3000 + '"}',
)
RELAYS = ("camera", "telemetry", "localization")
ANSWERING = ("drive", "queue", "chat")  # the channels that take messages, and answer each wrong one
VIEWERS = 10


@pytest.fixture(scope="module")
def lab(skill_server_address: str, tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[LiveServer, int]]:
    """The lab served, wired to the session's skill server, with a live class anyone may follow; its id."""
    from middleware.db import session_factory
    from middleware.models import User
    from middleware.models.teaching import GuidedSession, Tour

    tmp_path = tmp_path_factory.mktemp("hostile-messages")
    app = make_test_app(f"sqlite:///{tmp_path / 'lab.sqlite3'}", f"lab-1={skill_server_address}", tmp_path)
    with session_factory(app)() as session:
        for index in range(VIEWERS):
            add_test_account(session, f"viewer{index}", "student")
        tutor_id = session.query(User.id).filter_by(username="student1").scalar()
        tour = Tour(slug="hostile", title="Hostile", author_id=tutor_id,
                    steps_json=json.dumps([{"text": "Look.", "panel": "camera", "condition": {"type": "manual"}}]))
        session.add(tour)
        session.flush()
        live = GuidedSession(tour_id=tour.id, robot_name="lab-1", tutor_id=tutor_id, course_id=None)
        session.add(live)
        session.commit()
        session_id = live.id
    server = LiveServer(app)
    try:
        yield server, session_id
    finally:
        server.stop()
        _let_go(app)


@pytest.fixture(scope="module")
def student(lab: tuple[LiveServer, int]) -> LabClient:
    """student1, logged in once for the module (each test's sockets are closed when it ends)."""
    client = LabClient(lab[0].url)
    assert client.login() == 302
    return client


class LinkReader:
    """The page's side of a link: every message read is kept, by channel number."""

    def __init__(self, ws) -> None:
        self.ws = ws
        self.seen: list[tuple[int, str | bytes]] = []
        self.taken: set[int] = set()

    def read(self, timeout_s: float) -> tuple[int, str | bytes] | None:
        message = self.ws.receive(timeout=timeout_s)
        if message is None:
            return None
        if isinstance(message, bytes):
            entry: tuple[int, str | bytes] = (int.from_bytes(message[:4], "big"), message[4:])
        else:
            head, _, text = message.partition(" ")
            entry = (int(head), text)
        self.seen.append(entry)
        return entry

    def wait(self, predicate: Callable[[int, str | bytes], bool], timeout_s: float = 10.0) -> tuple[int, dict]:
        """The first message predicate accepts that no wait took yet (reading on), as (sub, decoded JSON): the
        channels interleave, so what one wait reads past, a later one finds."""
        for index, (sub, text) in enumerate(self.seen):
            if index not in self.taken and isinstance(text, str) and predicate(sub, text):
                self.taken.add(index)
                return sub, json.loads(text)
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            entry = self.read(max(0.05, deadline - time.monotonic()))
            if entry is not None and isinstance(entry[1], str) and predicate(*entry):
                self.taken.add(len(self.seen) - 1)
                return entry[0], json.loads(entry[1])
        texts = [(sub, text[:200]) for sub, text in self.seen if isinstance(text, str)]
        raise AssertionError(f"the expected message never came; the last text read: {texts[-8:]}")

    def control(self, kind: str, timeout_s: float = 10.0) -> dict:
        """The next control message (sub 0) of this type."""
        return self.wait(lambda sub, text: sub == 0 and _decoded(text).get("type") == kind, timeout_s)[1]

    def read_for(self, seconds: float) -> None:
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.read(max(0.01, deadline - time.monotonic()))

    def of(self, sub: int) -> list[dict]:
        return [_decoded(text) for s, text in self.seen if s == sub and isinstance(text, str)]

    def closed_subs(self) -> dict[int, dict]:
        return {m["sub"]: m for m in self.of(0) if m.get("type") == "closed"}


def _decoded(text: str | bytes) -> dict:
    try:
        value = json.loads(text)
    except ValueError:
        return {}
    return value if isinstance(value, dict) else {}


def _root(field: str) -> str:
    """The message's own field an error names ("path" of "path[0][0]")."""
    return field.split("[")[0].split(".")[0]


def _open_link(client: LabClient) -> LinkReader:
    link = LinkReader(client.websocket("/ws/link"))
    link.control("ready")
    return link


def _subscribe(link: LinkReader, sub: int, path: str) -> None:
    link.ws.send(json.dumps({"type": "subscribe", "sub": sub, "path": path}))


def _still_serves(link: LinkReader, sub: int = 99) -> None:
    """The link is open and opens a channel that streams."""
    _subscribe(link, sub, "/ws/robots/lab-1/telemetry")
    link.wait(lambda s, text: s == sub and _decoded(text).get("type") == "telemetry")


def test_every_hostile_control_message_gets_an_error_naming_its_field(student: LabClient) -> None:
    link = _open_link(student)
    for text in HOSTILE_CONTROL:
        link.ws.send(text)
        error = link.control("error")
        assert error["code"] == "invalid_field" and _root(error["field"]) in LINK_ERROR_FIELDS, (text[:80], error)
        assert error["message"], text[:80]
    link.ws.send(b"\x00\x00\x00\x01binary")
    assert link.control("error")["field"] == "message"
    _still_serves(link)
    assert not link.closed_subs()


def test_a_hostile_channel_path_closes_only_its_own_channel(student: LabClient, lab: tuple[LiveServer, int]) -> None:
    link = _open_link(student)
    _subscribe(link, 1, "/ws/robots/lab-1/telemetry")
    for sub, path in enumerate(HOSTILE_PATHS, start=2):
        _subscribe(link, sub, path)
        closed = link.wait(lambda s, text, sub=sub: s == 0 and _decoded(text).get("sub") == sub
                           and _decoded(text).get("type") == "closed")[1]
        assert closed["code"] in {4404, 4403, 1013}, (path, closed)
    _subscribe(link, 50, f"/ws/tour-sessions/{lab[1]}")
    link.wait(lambda s, text: s == 50 and _decoded(text).get("type") == "state")
    link.wait(lambda s, text: s == 1 and _decoded(text).get("type") == "telemetry")
    assert set(link.closed_subs()) == set(range(2, 2 + len(HOSTILE_PATHS)))


def test_every_channel_answers_hostile_messages_and_stays_open(student: LabClient, lab: tuple[LiveServer, int]) -> None:
    link = _open_link(student)
    paths = {**{name: f"/ws/robots/lab-1/{name}" for name in (*ANSWERING, *RELAYS)},
             "tour": f"/ws/tour-sessions/{lab[1]}"}
    subs = {name: index for index, name in enumerate(paths, start=1)}
    for name, path in paths.items():
        _subscribe(link, subs[name], path)
        link.wait(lambda s, text, sub=subs[name]: s == 0 and _decoded(text) == {"type": "subscribed", "sub": sub})
    link.wait(lambda s, text: s == subs["drive"] and _decoded(text).get("type") == "ready")
    for text in HOSTILE_CHANNEL:
        for sub in subs.values():
            link.ws.send(f"{sub} {text}")
        link.read_for(0.13)  # under every channel's 10 messages a second
    link.read_for(1.0)
    assert not link.closed_subs(), link.closed_subs()
    for name in ANSWERING:
        errors = [m for m in link.of(subs[name]) if m.get("type") == "error"]
        assert len(errors) == len(HOSTILE_CHANNEL), (name, errors)
        assert all(e["code"] == "invalid_field" and e["field"] for e in errors), (name, errors)
    link.taken = set(range(len(link.seen)))  # and each still does its work
    link.ws.send(f'{subs["drive"]} {json.dumps({"type": "stop", "sequence": 1})}')
    ack = link.wait(lambda s, text: s == subs["drive"] and _decoded(text).get("type") in {"ack", "error"})[1]
    assert ack["type"] == "ack" or ack["code"] != "invalid_field", ack
    link.ws.send(f'{subs["chat"]} {json.dumps({"type": "say", "body": "still here"})}')
    link.wait(lambda s, text: s == subs["chat"] and _decoded(text).get("type") == "sent")
    link.ws.send(f'{subs["queue"]} {json.dumps({"type": "leave"})}')
    link.wait(lambda s, text: s == subs["queue"] and _decoded(text).get("type") == "queue"
              and not _decoded(text)["in_queue"])
    link.wait(lambda s, text: s == subs["telemetry"] and _decoded(text).get("type") == "telemetry")
    assert not link.closed_subs(), link.closed_subs()


@pytest.mark.parametrize("channel", ANSWERING)
def test_a_channel_on_its_own_socket_answers_hostile_messages_and_stays_open(student: LabClient, channel: str) -> None:
    ws = student.websocket(f"/ws/robots/lab-1/{channel}")
    answers: list[dict] = []
    for text in HOSTILE_CHANNEL:
        ws.send(text)
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:
            message = _decoded(ws.receive(timeout=deadline - time.monotonic()) or "")
            if message.get("type") == "error":
                answers.append(message)
                break
        time.sleep(0.1)  # under the channel's 10 messages a second
    assert ws.connected, (ws.close_reason, ws.close_message)
    assert len(answers) == len(HOSTILE_CHANNEL) and all(a["code"] == "invalid_field" for a in answers), answers


hostile_text = st.one_of(st.text(max_size=12), st.sampled_from(("\ud800", "a\udfffb", "\x00", "²", "¹²³", "٣",
                                                                 "1" * 300, "subscribe", "/ws/robots/lab-1/chat")))
hostile_number = st.one_of(st.integers(-(2**70), 2**70), st.floats(allow_nan=True, allow_infinity=True))
hostile_scalar = st.one_of(st.none(), st.booleans(), hostile_number, hostile_text)


def _hostile_containers(inner: st.SearchStrategy) -> st.SearchStrategy:
    # A def: Hypothesis reads a lambda's source to see that it recurses, and misreads one split over lines.
    return st.lists(inner, max_size=3) | st.dictionaries(st.sampled_from(("type", "sub", "path", "id", "body")),
                                                         inner, max_size=3)


hostile_json = st.recursive(hostile_scalar, _hostile_containers, max_leaves=8)
control_messages = st.fixed_dictionaries(
    {"type": st.one_of(hostile_json, st.sampled_from(("subscribe", "unsubscribe")))},
    optional={"sub": hostile_json, "path": hostile_json})


def _as_text(value: object) -> str:
    """JSON text as a client writes it: NaN and Infinity as Python writes them, lone surrogates escaped."""
    return json.dumps(value)


def test_drawn_control_and_channel_messages_never_end_the_link(student: LabClient) -> None:
    link = _open_link(student)
    _subscribe(link, 1, "/ws/robots/lab-1/chat")
    link.wait(lambda s, text: s == 1 and _decoded(text).get("type") == "history")
    drawn = {"control": 0, "channel": 0}

    @settings(max_examples=60, deadline=None, derandomize=True, database=None,
              suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
    @given(message=control_messages, to_channel=st.booleans())
    def one_message(message: dict, to_channel: bool) -> None:
        if to_channel:
            drawn["channel"] += 1
            link.ws.send(f"1 {_as_text(message)}")
            link.wait(lambda s, text: s == 1 and _decoded(text).get("type") == "error")
            time.sleep(0.1)  # under the chat's 10 messages a second
            return
        drawn["control"] += 1
        sub = message.get("sub")
        if isinstance(sub, int) and not isinstance(sub, bool) and 0 < sub < 2**31:
            message["sub"] = "²"  # a valid sub would subscribe or unsubscribe: every drawn message is wrong somewhere
        link.ws.send(_as_text(message))
        error = link.control("error")
        assert error["code"] == "invalid_field" and _root(error["field"]) in LINK_ERROR_FIELDS, (message, error)

    one_message()
    assert link.ws.connected and 1 not in link.closed_subs()
    _still_serves(link)
    record = Path(__file__).resolve().parents[2] / "test-artifacts" / "hardening-hostile-messages.json"
    record.parent.mkdir(exist_ok=True)
    record.write_text(json.dumps({"drawn": drawn, "control_messages": len(HOSTILE_CONTROL),
                                  "channel_messages": len(HOSTILE_CHANNEL), "paths": len(HOSTILE_PATHS)}, indent=1))


def test_a_message_past_the_socket_limit_closes_it_as_too_big_not_as_a_failure(student: LabClient) -> None:
    """Past MAX_MESSAGE_BYTES the socket is closed unread (1009, RFC 6455's 'message too big'), by the bound on what
    a client may make the server buffer; within it, a channel's own smaller limit is an error on that message."""
    from simple_websocket import ConnectionClosed

    from middleware.realtime import MAX_MESSAGE_BYTES

    link = _open_link(student)
    link.ws.send(json.dumps({"type": "subscribe", "sub": 1, "path": "/ws/x", "pad": "x" * MAX_MESSAGE_BYTES}))
    deadline = time.monotonic() + 10.0
    with pytest.raises(ConnectionClosed):
        while time.monotonic() < deadline:
            link.read(1.0)
    assert link.ws.close_reason == 1009, (link.ws.close_reason, link.ws.close_message)


def test_one_pages_hostile_messages_leave_every_other_pages_channels_open(student: LabClient,
                                                                          lab: tuple[LiveServer, int]) -> None:
    """Ten people watch lab-1's chat and telemetry while one page sends every hostile message: the shared chat and
    telemetry keep reaching all ten, and none of their channels closes."""
    viewers = []
    for index in range(VIEWERS):
        client = LabClient(lab[0].url)
        assert client.login(f"viewer{index}", STUDENT_PASSWORD) == 302
        link = _open_link(client)
        _subscribe(link, 1, "/ws/robots/lab-1/chat")
        _subscribe(link, 2, "/ws/robots/lab-1/telemetry")
        link.wait(lambda s, text: s == 1 and _decoded(text).get("type") == "history")
        viewers.append(link)
    attacker = _open_link(student)
    _subscribe(attacker, 1, "/ws/robots/lab-1/chat")
    _subscribe(attacker, 2, "/ws/robots/lab-1/drive")
    attacker.wait(lambda s, text: s == 1 and _decoded(text).get("type") == "history")
    for control, message in zip(HOSTILE_CONTROL, HOSTILE_CHANNEL * 2, strict=False):
        attacker.ws.send(control)
        attacker.ws.send(f"1 {message}")
        attacker.ws.send(f"2 {message}")
        attacker.read_for(0.12)
    attacker.ws.send(f'1 {json.dumps({"type": "say", "body": "after the storm"})}')
    attacker.wait(lambda s, text: s == 1 and _decoded(text).get("type") == "sent")
    for link in viewers:
        link.wait(lambda s, text: s == 1 and (_decoded(text).get("message") or {}).get("body") == "after the storm")
        link.taken = set(range(len(link.seen)))
        link.wait(lambda s, text: s == 2 and _decoded(text).get("type") == "telemetry")
        assert not link.closed_subs(), link.closed_subs()
    assert not attacker.closed_subs(), attacker.closed_subs()
