"""The writer child copies the commands of every session it records with one query a tick, whatever the class's
size, and each session gets exactly what it would alone: its robot's commands after its cursor, from its start on."""

from __future__ import annotations

import copy
from pathlib import Path

from sqlalchemy import event

from middleware.recordings.keeping import _COMMANDS, Keeping, Settings, _Part

STARTED_S = 1000.0


def _command(robot: str, sent_unix_s: float, sequence: int) -> dict[str, object]:
    return {"robot_name": robot, "user_id": 1, "sent_unix_s": sent_unix_s, "sequence": sequence, "source": "pad",
            "action": "drive", "detail": "{}", "accepted": True, "outcome": ""}


def _part(recording_id: int, robot: str, started_unix_s: float, cursor: int = 0) -> _Part:
    return _Part(recording_id, robot, 1, started_unix_s, writer=None, key="worker:1", cursor=cursor)  # type: ignore[arg-type]


def test_every_recorded_session_gets_its_own_commands_from_one_query_a_tick(engine, tmp_path: Path) -> None:
    with engine.begin() as connection:  # three robots; lab-2's first commands came before its session began
        connection.execute(_COMMANDS.insert(), [_command(robot, STARTED_S + second, second)
                                                for second in range(6) for robot in ("lab-1", "lab-2", "lab-3")])
    keeping = Keeping(engine, Settings(tmp_path, "worker:1", 10**9, 10**9, 365))
    first_id = 3  # lab-3's first command: this session has copied that much already
    parts = [_part(1, "lab-1", STARTED_S), _part(2, "lab-2", STARTED_S + 3.0), _part(3, "lab-3", STARTED_S, first_id),
             _part(4, "lab-4", STARTED_S)]
    alone = {part.recording_id: keeping._new_commands([copy.copy(part)])[part.recording_id]  # as each would alone
             for part in parts}
    statements: list[str] = []
    event.listen(engine, "before_cursor_execute", lambda _c, _r, sql, *_: statements.append(sql))

    together = keeping._new_commands(parts)

    assert len(statements) == 1, statements
    assert together == alone
    assert [row[2] for row in together[2]] == [3, 4, 5]  # lab-2's, from its session's start (less half a second)
    assert len(together[3]) == 5 and together[4] == []
    assert [part.cursor for part in parts][:3] == [16, 17, 18]  # each part's cursor at its robot's last command
    assert keeping._new_commands(parts) == {1: [], 2: [], 3: [], 4: []}  # nothing copied twice
