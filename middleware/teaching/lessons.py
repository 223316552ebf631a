"""Lessons: checking and saving them, finding their videos, and the skill schema used to check cues."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from flask import current_app, has_app_context
from flask_babel import gettext  # type: ignore[import-untyped]
from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.access.commands import Commander
from middleware.errors import Refused
from middleware.models.accounts import utc_now
from middleware.models.teaching import Lesson
from middleware.teaching.command_form import SkillSchemas
from middleware.teaching.cues import Cue, CueError, parse_cue_track, to_webvtt
from middleware.validation import decimal_int

VIDEO_NAME = re.compile(r"^[a-z0-9][a-z0-9_-]{0,100}\.(webm|mp4)$")
SLUG = re.compile(r"^[a-z0-9][a-z0-9-]{0,63}$")
MAX_TITLE = 120
MAX_SUMMARY = 500
MAX_TOPICS, MAX_TOPIC = 10, 60


def normalise_topics(value: object) -> str:
    """Topics ("Sensors, odometry" or a list) as stored on tours and lessons: "odometry, sensors" (lower case,
    sorted, no repeats); ValueError names the problem. Recommendations match them to question topics."""
    if value is None:
        return ""
    if isinstance(value, str):
        value = value.split(",")
    if not isinstance(value, list) or not all(isinstance(t, str) for t in value):
        raise ValueError(gettext("topics must be text: names separated by commas."))
    topics = sorted({" ".join(t.split()).lower() for t in value} - {""})
    if len(topics) > MAX_TOPICS or any(len(t) > MAX_TOPIC for t in topics):
        raise ValueError(gettext("topics: at most %(max_topics)s names of at most %(max_topic)s characters each.",
                                 max_topics=MAX_TOPICS, max_topic=MAX_TOPIC))
    return ", ".join(topics)


def topic_list(text: str | None) -> list[str]:
    """The stored topics as a list."""
    return [t for t in (part.strip() for part in (text or "").split(",")) if t]


class LessonInvalid(Refused):
    """A lesson that cannot be saved (400 invalid_lesson): errors name the field, and the line for cue errors;
    the first one is the refusal's message and field, and the JSON lists them all."""

    def __init__(self, errors: list[CueError]) -> None:
        first = errors[0] if errors else CueError(0, "body", gettext("The lesson is not valid."))
        message = (gettext("%(message)s (line %(line)s)", message=first.message, line=first.line) if first.line
                   else first.message)
        super().__init__(400, "invalid_lesson", message, first.field)
        self.errors = errors

    def to_dict(self) -> dict[str, object]:
        """The error, and every error by line."""
        return {**super().to_dict(), "errors": [e.to_dict() for e in self.errors]}


@dataclass(frozen=True)
class LessonDraft:
    """A checked lesson, ready to store."""

    slug: str
    title: str
    summary: str
    video_name: str
    cues: list[Cue]
    topics: str = ""
    before_exam_id: int | None = None
    after_exam_id: int | None = None


def video_dir(instance_path: str) -> Path:
    """The folder of lesson videos, never in the code tree: `lessons/` in the shared folder every web host reads
    (TELELAB_SHARED_DIR, the app's SHARED_DIR) when the app sets one, else in the instance folder (one host's disk:
    with several web hosts a video uploaded on one would be missing on the others)."""
    shared = current_app.config.get("SHARED_DIR") if has_app_context() else None
    return Path(shared or instance_path) / "lessons"


def available_videos(instance_path: str) -> list[str]:
    """The video files a lesson may use."""
    folder = video_dir(instance_path)
    if not folder.is_dir():
        return []
    return sorted(p.name for p in folder.iterdir() if p.is_file() and VIDEO_NAME.fullmatch(p.name))


class VideoNotDeletable(Refused):
    """A video that cannot be deleted: the status, a stable code and a sentence naming the video."""

    def __init__(self, status: int, code: str, message: str) -> None:
        super().__init__(status, code, message, "video_name")


def unused_videos(session: Session, instance_path: str) -> list[str]:
    """The lesson videos no lesson plays (an upload never chosen, or one a lesson stopped using)."""
    used = set(session.scalars(select(Lesson.video_name)))
    return [name for name in available_videos(instance_path) if name not in used]


def delete_unused_video(session: Session, instance_path: str, name: str) -> None:
    """Deletes a lesson video that no lesson plays; VideoNotDeletable otherwise, and nothing changes."""
    if not VIDEO_NAME.fullmatch(name) or not (video_dir(instance_path) / name).is_file():
        raise VideoNotDeletable(404, "unknown_video", gettext("There is no lesson video by that name."))
    users = session.scalars(select(Lesson.title).where(Lesson.video_name == name).order_by(Lesson.title)).all()
    if users:
        raise VideoNotDeletable(409, "video_in_use", gettext("%(name)s is the video of %(lessons)s: give that lesson "
                                                               "another video first.", name=name,
                                                               lessons=", ".join(users)))
    (video_dir(instance_path) / name).unlink(missing_ok=True)


def _text(data: dict[str, object], name: str, limit: int, required: bool = True) -> str:
    value = data.get(name, "")
    if not isinstance(value, str):
        raise LessonInvalid([CueError(0, name, gettext("%(field)s must be text.", field=name))])
    value = value.strip()
    if required and not value:
        raise LessonInvalid([CueError(0, name, gettext("Give the lesson a %(name)s.", name=name))])
    if len(value) > limit:
        raise LessonInvalid([CueError(0, name, gettext("%(field)s has at most %(limit)s characters.", field=name,
                                                         limit=limit))])
    return value


def check_lesson(data: object, skills: SkillSchemas, videos: list[str]) -> LessonDraft:
    """A checked lesson from the editor's JSON: title, summary, slug, topics, video_name, cues (WebVTT or SRT)."""
    if not isinstance(data, dict):
        raise LessonInvalid([CueError(0, "body", gettext("Send a JSON object with title, video_name and cues."))])
    title = _text(data, "title", MAX_TITLE)
    summary = _text(data, "summary", MAX_SUMMARY, required=False)
    slug = data.get("slug") or re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-")[:64] or "lesson"
    if not isinstance(slug, str) or not SLUG.fullmatch(slug):
        raise LessonInvalid([CueError(0, "slug", gettext("slug may use lower-case letters, digits and '-' (at most "
                                                          "64)."))])
    video = data.get("video_name")
    if not isinstance(video, str) or video not in videos:
        choices = ", ".join(videos) or gettext("none yet: put a .webm or .mp4 file in the instance's lessons folder")
        raise LessonInvalid([CueError(0, "video_name", gettext("Choose one of the lesson videos (%(choices)s).",
                                                               choices=choices))])
    try:
        topics = normalise_topics(data.get("topics"))
    except ValueError as error:
        raise LessonInvalid([CueError(0, "topics", str(error))]) from None
    before, after = _exam_id(data, "before_exam_id"), _exam_id(data, "after_exam_id")
    cues, errors = parse_cue_track(data.get("cues"), skills)
    if errors:
        raise LessonInvalid(errors)
    return LessonDraft(slug, title, summary, video, cues, topics, before, after)


def _exam_id(data: dict[str, object], name: str) -> int | None:
    """A test's id, or None for no test ("" or null, as the editor's "No test" sends it)."""
    value = data.get(name)
    if value in (None, ""):
        return None
    number = decimal_int(value, 1) if isinstance(value, str) else value
    if isinstance(number, bool) or not isinstance(number, int) or not 1 <= number <= 2**62:
        raise LessonInvalid([CueError(0, name, gettext("%(name)s must name a test by its id, or be empty for none.",
                                                         name=name))])
    return number


def save_lesson(session: Session, draft: LessonDraft, author_id: int | None, lesson: Lesson | None = None) -> Lesson:
    """Creates or updates a lesson from a checked draft; the caller commits."""
    clash = session.scalar(select(Lesson).where(Lesson.slug == draft.slug))
    if clash is not None and clash is not lesson:
        raise LessonInvalid([CueError(0, "slug", gettext("Another lesson is called %(slug)s already.",
                                                          slug=repr(draft.slug)))])
    if lesson is None:
        lesson = Lesson(author_id=author_id)
        session.add(lesson)
    lesson.slug, lesson.title, lesson.summary, lesson.topics = draft.slug, draft.title, draft.summary, draft.topics
    lesson.video_name, lesson.cues_vtt = draft.video_name, to_webvtt(draft.cues)
    lesson.before_exam_id, lesson.after_exam_id = draft.before_exam_id, draft.after_exam_id
    lesson.updated_at = utc_now()
    session.flush()
    return lesson


def stored_cues(lesson: Lesson) -> list[Cue]:
    """The cues of a stored lesson (its track was checked on save; re-read without a schema)."""
    cues, errors = parse_cue_track(lesson.cues_vtt, None)
    if errors:  # only if the row was edited by hand
        raise LessonInvalid(errors)
    return cues


def lesson_dict(lesson: Lesson, with_cues: bool = True) -> dict[str, object]:
    """JSON-ready form of a lesson."""
    data: dict[str, object] = {"id": lesson.id, "slug": lesson.slug, "title": lesson.title,
                               "summary": lesson.summary, "video_name": lesson.video_name,
                               "topics": topic_list(lesson.topics), "before_exam_id": lesson.before_exam_id,
                               "after_exam_id": lesson.after_exam_id}
    if with_cues:
        data["cues"] = [c.to_dict() for c in stored_cues(lesson)]
        data["cues_vtt"] = lesson.cues_vtt
    return data


def place_for_lesson(robot: Commander, practice: bool) -> dict[str, str]:
    """Where the robot starts a lesson ("dock" or "here") and a sentence: a lesson's video starts at the dock (the
    demo's is recorded on a fresh robot there, and a tutor records theirs from it), so the learner's practice robot
    is carried there and its picture starts as the video's; a lab robot is shared and stays where it stands."""
    if practice:
        robot.return_to_dock()
        return {"at": "dock", "message": gettext("Your practice robot is at its dock, where the lesson's video "
                                                 "starts.")}
    return {"at": "here", "message": gettext("%(robot)s starts where it stands; the video starts at the dock, so their "
                                             "pictures differ until it is docked (Return to the dock, on its map).",
                                             robot=robot.robot_name)}
