"""Lesson video uploads: only WebM or MP4 (by extension and by their first bytes), under a size limit,
stored under a name the server makes up (the client's file name is never used as a path).
"""

from __future__ import annotations

import os
import secrets
from datetime import UTC, datetime
from pathlib import Path
from typing import IO

from flask_babel import gettext  # type: ignore[import-untyped]

from middleware.errors import Refused, written_number
from middleware.teaching.lessons import VIDEO_NAME, video_dir

DEFAULT_MAX_VIDEO_BYTES = 200 * 1024 * 1024
MULTIPART_OVERHEAD = 64 * 1024  # the form's other fields and part headers, on top of the file
CHUNK = 1024 * 1024
EBML_MAGIC = b"\x1a\x45\xdf\xa3"  # WebM is Matroska, which starts with an EBML header
FIELD = "video"


class UploadRefused(Refused):
    """The upload cannot be kept: the status, a stable code and a sentence; the field is always the video."""

    def __init__(self, status: int, code: str, message: str) -> None:
        super().__init__(status, code, message, FIELD)


def extension_of(filename: str | None) -> str:
    """The lower-case extension of the client's file name ("webm" or "mp4"); UploadRefused otherwise."""
    suffix = Path((filename or "").replace("\\", "/")).suffix.lower().lstrip(".")
    if suffix not in {"webm", "mp4"}:
        raise UploadRefused(400, "invalid_video_type", gettext("video must be a .webm or .mp4 file."))
    return suffix


def matches_magic(extension: str, head: bytes) -> bool:
    """Whether the first bytes are those of the format the extension names."""
    if extension == "webm":
        return head[:4] == EBML_MAGIC
    return len(head) >= 8 and head[4:8] == b"ftyp"


def generated_name(extension: str, now: datetime | None = None) -> str:
    """A fresh file name for an upload: upload-<date>-<random>.<ext>, one of the names lessons accept."""
    stamp = (now or datetime.now(UTC)).strftime("%Y%m%d")
    name = f"upload-{stamp}-{secrets.token_hex(8)}.{extension}"
    assert VIDEO_NAME.fullmatch(name)
    return name


def store_video(instance_path: str, filename: str | None, stream: IO[bytes], max_bytes: int) -> str:
    """Checks and stores one uploaded video; its new name, or UploadRefused (nothing is left behind)."""
    extension = extension_of(filename)
    head = stream.read(12)
    if not head:
        raise UploadRefused(400, "empty_video", gettext("video is empty: choose a .webm or .mp4 file."))
    if not matches_magic(extension, head):
        kind = "WebM" if extension == "webm" else "MP4"
        raise UploadRefused(400, "invalid_video_content",
                            gettext("video is not a %(kind)s file: its content does not match the .%(extension)s "
                                    "extension.", kind=kind, extension=extension))
    folder = video_dir(instance_path)
    folder.mkdir(parents=True, exist_ok=True)
    name = generated_name(extension)
    partial = folder / f".{name}.part"  # not a name lessons accept, so never listed while it is written
    size = len(head)
    try:
        with open(partial, "xb") as out:
            out.write(head)
            while chunk := stream.read(CHUNK):
                size += len(chunk)
                if size > max_bytes:
                    raise UploadRefused(413, "video_too_large", too_large_message(max_bytes))
                out.write(chunk)
        os.replace(partial, folder / name)
    finally:
        partial.unlink(missing_ok=True)
    return name


def too_large_message(max_bytes: int) -> str:
    """The sentence for a video over the limit."""
    return str(gettext("video is too large: at most %(megabytes)s MB.",
                       megabytes=written_number(max_bytes // (1024 * 1024))))
