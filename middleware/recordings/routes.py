"""Recordings: the list, the replay page, the data it draws, the exports, and the admin's storage page. Every
recording is answered only to whom may see it (services.visible_recording): another's is a 404."""

from __future__ import annotations

import math
import re
from pathlib import Path

from flask import Blueprint, Response, current_app, jsonify, redirect, render_template, request, url_for
from flask.typing import ResponseReturnValue
from flask_babel import gettext  # type: ignore[import-untyped]
from flask_login import current_user, login_required

from middleware.api.contract import BOOLEAN, ID, OBJECT, array, described, file_answer, nullable, number, obj, whole
from middleware.db import after_commit, get_session
from middleware.errors import ApiError, Refused, written_number
from middleware.models.accounts import Role, User, as_utc
from middleware.models.recordings import RECORDING_KINDS, Recording
from middleware.recordings import export, files, services
from middleware.recordings.parts import recordings_of

blueprint = Blueprint("recordings", __name__)
MAX_RANGE_S = 7 * 24 * 3600.0


def _user() -> User:
    return current_user._get_current_object()


def _summary(recording: Recording, owner: str | None = None) -> dict[str, object]:
    return {"id": recording.id, "user_id": recording.user_id, "username": owner, "robot_name": recording.robot_name,
            "kind": recording.kind, "ref_id": recording.ref_id, "started_at": services.as_iso(recording.started_at),
            "ended_at": services.as_iso(recording.ended_at), "end_reason": recording.end_reason,
            "status": recording.status, "command_count": recording.command_count,
            "skill_count": recording.skill_count, "plan_count": recording.plan_count,
            "size_bytes": recording.size_bytes, "has_source": bool(recording.source_text)}


def _owner_names(recordings: list[Recording]) -> dict[int, str]:
    ids = {r.user_id for r in recordings}
    if not ids:
        return {}
    users = get_session().query(User).filter(User.id.in_(ids))
    return {u.id: u.username for u in users}


def _root() -> Path:
    return recordings_of(current_app).settings.directory


_CHANNELS = ("odometry", "ground_truth", "sonar", "laser", "localization", "commands", "goals", "camera")


def _data(recording: Recording, from_s: float = 0.0, to_s: float | None = None) -> dict[str, object]:
    """The decoded window: only the chunks in it are read from a complete part (the page asks for its first
    seconds first, so a long recording's first frame does not wait for all of it)."""
    root = _root()
    t0 = files.first_log_ns(root, recording.id)
    windowed = t0 is not None and (from_s > 0 or to_s is not None)
    messages = files.read_recording(root, recording.id, t0 + int(from_s * 1e9) if windowed and t0 else None,
                                    t0 + int(to_s * 1e9) if windowed and t0 and to_s is not None else None)
    data = export.replay_data(messages, services.may_see_truth(_user()), from_s, to_s, t0)
    if recording.ended_at is not None:
        data["recording_s"] = round((as_utc(recording.ended_at) - as_utc(recording.started_at)).total_seconds(), 3)
    return data


def _seconds(name: str) -> float | None:
    """A time query parameter: a finite number of seconds from 0 to MAX_RANGE_S, or None when absent."""
    raw = request.args.get(name)
    if raw is None or raw == "":
        return None
    try:
        value = float(raw)
    except ValueError:
        value = math.nan
    if not math.isfinite(value) or not 0.0 <= value <= MAX_RANGE_S or len(raw) > 32:
        raise ApiError(400, "invalid_field", gettext("%(name)s must be a number of seconds from 0 to %(high)s.",
                                                     name=name, high=written_number(MAX_RANGE_S, ".0f")), name)
    return value


def _range() -> tuple[float, float | None]:
    from_s, to_s = _seconds("from_s") or 0.0, _seconds("to_s")
    if to_s is not None and to_s < from_s:
        raise ApiError(400, "invalid_field", gettext("to_s must not be before from_s."), "to_s")
    return from_s, to_s


@blueprint.get("/recordings")
@login_required
def index_page() -> ResponseReturnValue:
    """The recordings the user may see."""
    recordings = services.visible_recordings(get_session(), _user())
    names = _owner_names(recordings)
    return render_template("recordings/index.html", recordings=[_summary(r, names.get(r.user_id))
                                                                for r in recordings])


@blueprint.get("/recordings/<int:recording_id>")
@login_required
def replay_page(recording_id: int) -> ResponseReturnValue:
    """The replay page of one recording."""
    recording = services.visible_recording(get_session(), _user(), recording_id)
    names = _owner_names([recording])
    return render_template("recordings/replay.html", recording=_summary(recording, names.get(recording.user_id)),
                           truth=services.may_see_truth(_user()), channels=export.CSV_CHANNELS)


@blueprint.get("/recordings/of/<kind>/<int:ref_id>")
@login_required
def run_of(kind: str, ref_id: int) -> ResponseReturnValue:
    """The replay of an attempt's, a trial's or an exercise run's session (the result pages link here)."""
    recording = services.recording_for(get_session(), _user(), kind, ref_id) if kind in RECORDING_KINDS else None
    if recording is None:
        raise Refused(404, "unknown_recording", gettext("This run was not recorded, or you may not see it."))
    return redirect(url_for("recordings.replay_page", recording_id=recording.id))


@blueprint.get("/admin/recordings")
@login_required
def storage_page() -> ResponseReturnValue:
    """Admins: the recordings' disk use per user against the limits."""
    if _user().role != Role.ADMIN:
        raise Refused(403, "forbidden", gettext("Only an admin sees the recordings' storage."))
    settings = recordings_of(current_app).settings
    rows = services.storage_by_user(get_session())
    return render_template("recordings/storage.html", rows=rows, total=sum(r[3] for r in rows), settings=settings)


@blueprint.get("/api/recordings")
@login_required
@described(query={"offset": whole(0, 1_000_000)}, answers={200: obj(("recordings",), recordings=array(OBJECT))})
def list_recordings() -> ResponseReturnValue:
    """The recordings the user may see, newest first (200 a page)."""
    offset = int(request.args.get("offset", "0"))
    recordings = services.visible_recordings(get_session(), _user(), offset=offset)
    names = _owner_names(recordings)
    return jsonify({"recordings": [_summary(r, names.get(r.user_id)) for r in recordings]})


@blueprint.get("/api/recordings/<int:recording_id>")
@login_required
@described(answers={200: obj(("recording",), recording=OBJECT)})
def recording_summary(recording_id: int) -> ResponseReturnValue:
    """One recording's index row."""
    recording = services.visible_recording(get_session(), _user(), recording_id)
    return jsonify({"recording": _summary(recording, _owner_names([recording]).get(recording.user_id))})


@blueprint.get("/api/recordings/<int:recording_id>/data")
@login_required
@described(query={"from_s": number(0, MAX_RANGE_S), "to_s": number(0, MAX_RANGE_S)},
           answers={200: obj(("t0_unix_s", "duration_s", "truth", "scene", "info", *_CHANNELS, "measurement"),
                             description="export.replay_data: each channel a list of [t_s, ...] rows",
                             t0_unix_s=number(), duration_s=number(), truth=BOOLEAN, scene=nullable(OBJECT),
                             info=nullable(OBJECT), recording_s=number(), measurement=nullable(OBJECT),
                             **{channel: array() for channel in _CHANNELS})})
def recording_data(recording_id: int) -> ResponseReturnValue:
    """The decoded channels from from_s to to_s (seconds from the first message): what the replay page draws."""
    recording = services.visible_recording(get_session(), _user(), recording_id)
    from_s, to_s = _range()
    return jsonify({**_data(recording, from_s, to_s),
                    "measurement": services.attempt_measurement(get_session(), recording)})


@blueprint.get("/api/recordings/<int:recording_id>/export.mcap")
@login_required
@described(answers={200: file_answer("application/octet-stream", "the recording as one MCAP file")})
def export_mcap(recording_id: int) -> ResponseReturnValue:
    """The recording as one MCAP file (Foxglove opens it); without the ground truth unless the user may see it."""
    recording = services.visible_recording(get_session(), _user(), recording_id)
    messages = export.allowed(files.read_recording(_root(), recording.id), services.may_see_truth(_user()))
    body = export.merged_mcap(messages, {"recording_id": str(recording.id), "robot": recording.robot_name,
                                         "kind": recording.kind})
    return Response(body, mimetype="application/octet-stream", headers={
        "Content-Disposition": f'attachment; filename="recording-{recording.id}.mcap"'})


@blueprint.get("/api/recordings/<int:recording_id>/export/<channel>.csv")
@login_required
@described(answers={200: file_answer("text/csv", "one channel as CSV")})
def export_csv(recording_id: int, channel: str) -> ResponseReturnValue:
    """One channel (odometry, ground_truth, sonar, laser, localization, commands, goals) as CSV."""
    recording = services.visible_recording(get_session(), _user(), recording_id)
    if channel not in export.CSV_CHANNELS or (channel == "ground_truth" and not services.may_see_truth(_user())):
        raise ApiError(404, "unknown_channel", gettext("There is no such channel in this recording."), "channel")
    root = _root()
    data = export.replay_data(files.read_recording(root, recording.id), services.may_see_truth(_user()),
                              t0_ns=files.first_log_ns(root, recording.id), laser_every_s=0.0)
    text = export.channel_csv(data, channel)
    return Response(text, mimetype="text/csv", headers={
        "Content-Disposition": f'attachment; filename="recording-{recording.id}-{channel}.csv"'})


@blueprint.get("/api/recordings/<int:recording_id>/camera/<int:index>")
@login_required
@described(answers={200: file_answer("image/jpeg", "one recorded camera frame")})
def camera_frame(recording_id: int, index: int) -> ResponseReturnValue:
    """The index-th JPEG frame recorded while someone watched the server camera."""
    recording = services.visible_recording(get_session(), _user(), recording_id)
    jpeg = export.camera_frame(files.read_recording(_root(), recording.id), index)
    if jpeg is None:
        raise ApiError(404, "unknown_frame", gettext("This recording has no such camera frame."), "index")
    return Response(jpeg, mimetype="image/jpeg", headers={"Cache-Control": "private, max-age=3600"})


@blueprint.get("/api/recordings/<int:recording_id>/source")
@login_required
@described(answers={200: file_answer("text/plain", "the plan or code that produced the run")})
def export_source(recording_id: int) -> ResponseReturnValue:
    """The plan or code that produced the run."""
    recording = services.visible_recording(get_session(), _user(), recording_id)
    if not recording.source_text:
        raise ApiError(404, "no_source", gettext("No plan or code produced this run: it was driven by hand."),
                       "recording_id")
    name = re.sub(r"[^A-Za-z0-9_.-]", "_", recording.source_name or f"recording-{recording.id}.txt")[:80]
    return Response(recording.source_text, mimetype="text/plain", headers={
        "Content-Disposition": f'attachment; filename="{name}"'})


@blueprint.get("/api/recordings/of/<kind>/<int:ref_id>")
@login_required
@described(answers={200: obj(("recording",), recording=OBJECT)})
def recording_of(kind: str, ref_id: int) -> ResponseReturnValue:
    """The newest recording of an attempt, a trial, an exercise run (kind) the user may see."""
    if kind not in RECORDING_KINDS:
        raise ApiError(404, "unknown_kind", gettext("There is no such kind of session."), "kind")
    recording = services.recording_for(get_session(), _user(), kind, ref_id)
    if recording is None:
        raise ApiError(404, "unknown_recording", gettext("This run was not recorded."), "ref_id")
    return jsonify({"recording": _summary(recording)})


@blueprint.delete("/api/recordings/<int:recording_id>")
@login_required
@described(answers={200: obj(("deleted",), deleted=ID)})
def delete_recording(recording_id: int) -> ResponseReturnValue:
    """Deletes a recording (its owner or an admin), files after the commit."""
    user = _user()
    recording = services.visible_recording(get_session(), user, recording_id)
    if recording.user_id != user.id and user.role != Role.ADMIN:
        raise Refused(403, "forbidden", gettext("Only its owner or an admin deletes a recording."))
    if recording.ended_at is None:
        raise Refused(409, "still_recording", gettext("This session is still being recorded: delete it once it "
                                                      "ended."))
    get_session().delete(recording)
    root = _root()
    after_commit(lambda: files.remove_recording(root, recording_id))
    return jsonify({"deleted": recording_id})

