"""A worker that leaves (a rolling restart's SIGTERM) answers every chat line its sockets have read before it closes
them with 1012: twelve students, half on sockets of their own and half on the page's link, each with a line in the
chat's handler at the moment the drain begins. The handler is held (in this process: the server runs in the test's
own) so that every line is surely read and unanswered when the drain starts."""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Iterator

import pytest
import simple_websocket
from sqlalchemy import select

from tests.conftest import LabClient, add_test_account

STUDENTS = 12
CHAT = "/ws/robots/lab-1/chat"


@pytest.fixture
def draining_loop() -> Iterator[None]:
    """The test process's channel loop, told to stop draining afterwards (it serves the next tests too)."""
    from middleware.live.loop import channel_loop

    yield
    channel_loop().draining = False


class Chat:
    """A student's chat, on a socket of its own or as sub 1 of a link."""

    def __init__(self, client: LabClient, on_link: bool) -> None:
        self.on_link = on_link
        self.ws = client.websocket("/ws/link" if on_link else CHAT)
        if on_link:
            self.ws.send(json.dumps({"type": "subscribe", "sub": 1, "path": CHAT}))
        assert self.next()["type"] == "history"

    def next(self) -> dict:
        """The chat's next message (a link's control messages skipped)."""
        while True:
            raw = self.ws.receive(timeout=20)
            assert raw is not None, "nothing came"
            if not self.on_link:
                return json.loads(raw)
            sub, _, text = raw.partition(" ")
            if sub == "1":
                return json.loads(text)

    def say(self, line: str) -> None:
        command = json.dumps({"type": "say", "body": line})
        self.ws.send(f"1 {command}" if self.on_link else command)

    def answer_then_close(self) -> tuple[int | None, int]:
        """(the id the line was stored as, the socket's close code)."""
        sent = None
        try:
            while True:
                message = self.next()
                if message["type"] == "sent":
                    sent = message["id"]
        except simple_websocket.ConnectionClosed as closed:
            return sent, closed.reason


def test_a_leaving_worker_answers_the_lines_it_read_then_closes_every_socket_with_1012(
        app, live_server, monkeypatch, draining_loop) -> None:
    from middleware.chat import services
    from middleware.db import session_factory
    from middleware.live.loop import channel_loop, drain_channels
    from middleware.models import ChatMessage

    with session_factory(app)() as session:
        for n in range(1, STUDENTS):
            add_test_account(session, f"writer{n}", "student")
        session.commit()
    chats = []
    for n in range(STUDENTS):
        client = LabClient(live_server.url)
        assert client.login("student1" if n == 0 else f"writer{n}") == 302
        chats.append(Chat(client, on_link=n % 2 == 1))

    in_handler, release = threading.Semaphore(0), threading.Event()
    post_message = services.post_message

    def held_post(*args, **kwargs):
        in_handler.release()
        release.wait(20)
        return post_message(*args, **kwargs)

    monkeypatch.setattr(services, "post_message", held_post)
    for n, chat in enumerate(chats):
        chat.say(f"line of student {n}")
    for _ in chats:
        assert in_handler.acquire(timeout=20), "a line never reached the chat's handler"

    drain_channels()  # what a leaving worker's SIGTERM does
    time.sleep(0.3)
    assert all(chat.ws.connected for chat in chats), "a socket closed with its line unanswered"
    release.set()
    endings = [chat.answer_then_close() for chat in chats]
    assert channel_loop().wait_drained(10)

    assert [code for _, code in endings] == [1012] * STUDENTS
    assert all(sent is not None for sent, _ in endings), endings
    with session_factory(app)() as session:
        stored = dict(session.execute(select(ChatMessage.id, ChatMessage.body)).all())
    assert [stored.get(sent) for sent, _ in endings] == [f"line of student {n}" for n in range(STUDENTS)]
