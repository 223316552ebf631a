"""xAPI statements to the Learning Record Store through a durable outbox (xapi_outbox): the elected process builds
the statements of what happened lately, queues those not queued yet (a statement's id is unique, so once), and
sends each with PUT /statements?statementId=<id> (idempotent at the LRS). A failure keeps the row pending with the
reason and a later try (backoff doubling from RETRY_BASE_S to RETRY_MAX_S); a restart loses nothing, as the rows
are the truth. An LRS that refuses a statement for good (400, 409, 413) marks it failed, with its answer."""

from __future__ import annotations

import json
import logging
import threading
import uuid
from collections.abc import Callable
from datetime import datetime, timedelta
from urllib.parse import quote

import requests
from flask import Flask
from sqlalchemy import delete, func, or_, select, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from middleware import db
from middleware.analytics.settings import XapiSettings
from middleware.analytics.statements import XAPI_VERSION, StatementBuilder
from middleware.analytics.xapi_schema import statement_errors
from middleware.locking import ClusterElection
from middleware.models.accounts import as_utc, utc_now
from middleware.models.analytics import XapiStatement

log = logging.getLogger(__name__)
LOOKBACK = timedelta(days=7)  # what happened this long ago is still queued if it was not (a lab down for days)
KEPT_SENT = timedelta(days=30)  # sent rows kept past the look-back, so nothing is queued twice
RETRY_BASE_S = 30.0
RETRY_MAX_S = 3600.0
CLAIM_S = 120.0
BATCH = 50
TIMEOUT_S = 10.0
FINAL_REFUSALS = (400, 409, 413)
XAPI_OUTBOX_LOCK = 0x7E1E_A9A1  # the advisory lock that elects the one process queueing statements


def queue_new(session: Session, homepage: str, now: datetime) -> int:
    """Queues the statements of what ended within LOOKBACK that are not queued yet; how many were queued. One that
    fails the statement schema is queued as failed, with the reason (it would never be accepted)."""
    built = StatementBuilder(session, homepage).built(None, now - LOOKBACK, now)
    ids = [b.statement["id"] for b in built]
    known: set[str] = set()
    for start in range(0, len(ids), 500):
        known |= set(session.scalars(select(XapiStatement.statement_id)
                                     .where(XapiStatement.statement_id.in_(ids[start:start + 500]))))
    added = 0
    for one in built:
        statement = one.statement
        if statement["id"] in known:
            continue
        errors = statement_errors(statement)
        session.add(XapiStatement(statement_id=statement["id"], user_id=one.user_id,
                                  statement_json=json.dumps(statement, sort_keys=True),
                                  status="failed" if errors else "pending", tries=0, next_try_at=now,
                                  last_error="; ".join(errors)[:2000] if errors else None, created_at=now))
        known.add(statement["id"])
        added += 1
    session.flush()
    return added


def _claim(sessions: Callable[[], Session], now: datetime, key: str) -> list[int]:
    with sessions() as session, session.begin():
        due = list(session.scalars(select(XapiStatement.id).where(
            XapiStatement.status == "pending", XapiStatement.next_try_at <= now,
            or_(XapiStatement.claimed_until.is_(None), XapiStatement.claimed_until < now))
            .order_by(XapiStatement.id).limit(BATCH)))
        claimed = []
        for row_id in due:
            taken = session.execute(update(XapiStatement).where(
                XapiStatement.id == row_id, XapiStatement.status == "pending",
                or_(XapiStatement.claimed_until.is_(None), XapiStatement.claimed_until < now))
                .values(claimed_by=key, claimed_until=now + timedelta(seconds=CLAIM_S)))
            if taken.rowcount:  # type: ignore[attr-defined]
                claimed.append(row_id)
        return claimed


def put_statement(http: requests.Session, settings: XapiSettings, statement_id: str, body: str) -> requests.Response:
    """PUT one statement to the LRS (xAPI 1.0.3 Part Three, 2.1: the statement resource)."""
    assert settings.lrs_url is not None
    url = f"{settings.lrs_url.rstrip('/')}/statements?statementId={quote(statement_id)}"
    auth = (settings.username, settings.password) if settings.username else None
    return http.put(url, data=body.encode(), auth=auth, timeout=TIMEOUT_S,
                    headers={"Content-Type": "application/json", "X-Experience-API-Version": XAPI_VERSION})


def _outcome(http: requests.Session, settings: XapiSettings, statement_id: str, body: str) -> tuple[str, str | None]:
    """('sent' | 'pending' | 'failed', the reason) of one try."""
    try:
        answer = put_statement(http, settings, statement_id, body)
    except requests.RequestException as error:
        return "pending", f"The LRS could not be reached ({type(error).__name__})."
    if answer.status_code in (200, 204):
        return "sent", None
    body = " ".join(answer.text.split())[:200]
    reason = f"The LRS answered {answer.status_code} {answer.reason or ''}".rstrip() + (f": {body}" if body else ".")
    return ("failed" if answer.status_code in FINAL_REFUSALS else "pending"), reason


def send_due(sessions: Callable[[], Session], settings: XapiSettings, now: datetime | None = None,
             http: requests.Session | None = None) -> tuple[int, int]:
    """Sends every statement due now that this process claims; (sent, not sent)."""
    moment = now or utc_now()
    key = uuid.uuid4().hex[:12]
    client = http or requests.Session()
    sent = missed = 0
    for row_id in _claim(sessions, moment, key):
        with sessions() as session:
            row = session.get(XapiStatement, row_id)
            if row is None or row.claimed_by != key:
                continue
            statement_id, body = row.statement_id, row.statement_json
        status, reason = _outcome(client, settings, statement_id, body)
        with sessions() as session, session.begin():
            row = session.get(XapiStatement, row_id)
            if row is None:
                continue
            row.claimed_by, row.claimed_until, row.tries = None, None, row.tries + 1
            row.status, row.last_error = status, reason
            if status == "sent":
                row.sent_at = utc_now()
                sent += 1
            else:
                row.next_try_at = moment + timedelta(seconds=min(RETRY_BASE_S * 2 ** (row.tries - 1), RETRY_MAX_S))
                missed += 1
                log.warning("xAPI statement %s not sent (try %s): %s", statement_id, row.tries, reason)
    return sent, missed


def prune(session: Session, now: datetime) -> None:
    """Forgets statements sent long ago (past the look-back, so they are never queued again)."""
    session.execute(delete(XapiStatement).where(XapiStatement.status == "sent",
                                                XapiStatement.sent_at < now - KEPT_SENT))


def outbox_status(session: Session) -> dict[str, object]:
    """How many statements wait, were sent, failed for good, and the latest reason one was not sent."""
    counts = dict(session.execute(select(XapiStatement.status, func.count()).group_by(XapiStatement.status)).all())
    latest = session.execute(select(XapiStatement.last_error, XapiStatement.next_try_at)
                             .where(XapiStatement.last_error.is_not(None))
                             .order_by(XapiStatement.id.desc()).limit(1)).first()
    return {"pending": int(counts.get("pending", 0)), "sent": int(counts.get("sent", 0)),
            "failed": int(counts.get("failed", 0)), "last_error": latest[0] if latest else None,
            "next_try_at": as_utc(latest[1]).isoformat() if latest else None}


class XapiSender:
    """Every settings.interval_s, in the elected process: queue what is new, send what is due, forget old rows."""

    def __init__(self, app: Flask, settings: XapiSettings) -> None:
        self.settings = settings
        self._sessions = db.session_factory(app)
        self._election = ClusterElection(self._sessions.kw["bind"], XAPI_OUTBOX_LOCK)
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()

    def start(self) -> None:
        """Starts the loop once (each request calls it; only the first starts it)."""
        with self._lock:
            if self._thread is None and self.settings.sends:
                self._thread = threading.Thread(target=self._run, name="xapi-sender", daemon=True)
                self._thread.start()

    def stop(self) -> None:
        """Stops the loop (tests, shut-down) and gives the election up."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(5)
        self._election.resign()

    def run_once(self, now: datetime | None = None) -> tuple[int, int]:
        """One pass: queue, send, prune; (sent, not sent)."""
        moment = now or utc_now()
        assert self.settings.homepage is not None
        try:
            with self._sessions() as session, session.begin():
                queue_new(session, self.settings.homepage, moment)
                prune(session, moment)
        except IntegrityError:  # a former leader queued the same statements a moment ago: theirs stand
            log.info("xAPI statements were queued by another process at the same time")
        return send_due(self._sessions, self.settings, moment)

    def _run(self) -> None:
        while not self._stop.wait(self.settings.interval_s):
            if not self._election.leads():
                continue
            try:
                self.run_once()
            except Exception:  # noqa: BLE001 - a database or LRS away: the next pass tries again
                log.exception("xAPI sender")
