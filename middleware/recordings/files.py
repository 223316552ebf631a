"""A recording's files: MCAP parts in the shared recordings directory (one per process that recorded the session:
a take-over after a crash starts a new part), written chunked and flushed every FLUSH_S, and read back up to the
last complete chunk of each part, whatever cut the file."""

from __future__ import annotations

import io
import os
import shutil
import struct
import threading
import time
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import IO

import zstandard
from google.protobuf.message import Message
from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap.records import Channel, Chunk, Schema
from mcap.records import Message as McapMessage
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap.writer import CompressionType, Writer
from mcap_protobuf.schema import register_schema

from middleware.recordings import channels

FLUSH_S = 1.0  # a crash loses at most this much: the chunk in progress is closed and written this often
CHUNK_BYTES = 256 * 1024
PART_PREFIX = "part-"


def recording_dir(root: Path, recording_id: int) -> Path:
    """Where the recording's parts live."""
    return root / f"{int(recording_id):010d}"


def new_part_path(root: Path, recording_id: int, process_key: str) -> Path:
    """A new part's path (numbered after the parts already there), its directory made."""
    folder = recording_dir(root, recording_id)
    folder.mkdir(parents=True, exist_ok=True)
    taken = len(list(folder.glob(f"{PART_PREFIX}*.mcap")))
    safe_key = "".join(c if c.isalnum() or c in "-." else "_" for c in process_key)[:80]
    return folder / f"{PART_PREFIX}{taken:03d}-{safe_key}.mcap"


def part_paths(root: Path, recording_id: int) -> list[Path]:
    """The recording's parts in the order they were started."""
    return sorted(recording_dir(root, recording_id).glob(f"{PART_PREFIX}*.mcap"))


def size_on_disk(root: Path, recording_id: int) -> int:
    """The bytes its parts take."""
    return sum(path.stat().st_size for path in part_paths(root, recording_id))


def remove_recording(root: Path, recording_id: int) -> None:
    """Deletes its files."""
    shutil.rmtree(recording_dir(root, recording_id), ignore_errors=True)


class PartWriter:
    """One part: protobuf messages on the recording's topics, chunks closed and written (fsync) every FLUSH_S."""

    def __init__(self, target: Path | IO[bytes], metadata: dict[str, str], chunk_bytes: int = CHUNK_BYTES) -> None:
        self._file: IO[bytes] = open(target, "wb") if isinstance(target, Path) else target  # noqa: SIM115
        self._writer = Writer(self._file, chunk_size=chunk_bytes, compression=CompressionType.ZSTD)
        self._writer.start(profile="", library="telelab recorder")
        self._writer.add_metadata("session", metadata)
        self._channels: dict[str, int] = {}
        self._sequences: dict[str, int] = {}
        self._lock = threading.Lock()
        self._flushed_at = time.monotonic()
        self._finished = False

    def write(self, topic: str, message: Message, log_time_ns: int) -> None:
        """Adds one message (log time in unix ns)."""
        self._add(topic, type(message), message.SerializeToString(), log_time_ns)

    def write_serialized(self, topic: str, data: bytes, log_time_ns: int) -> None:
        """Adds one message already serialized as its topic's type (channels.MESSAGE_TYPES)."""
        self._add(topic, channels.MESSAGE_TYPES[topic], data, log_time_ns)

    def _add(self, topic: str, message_type: type[Message], data: bytes, log_time_ns: int) -> None:
        with self._lock:
            if self._finished:
                return
            channel_id = self._channels.get(topic)
            if channel_id is None:
                schema_id = register_schema(self._writer, message_type)
                channel_id = self._channels[topic] = self._writer.register_channel(
                    topic=topic, message_encoding="protobuf", schema_id=schema_id)
            sequence = self._sequences[topic] = self._sequences.get(topic, -1) + 1
            self._writer.add_message(channel_id=channel_id, log_time=log_time_ns, publish_time=log_time_ns,
                                     data=data, sequence=sequence)

    def flush_if_due(self) -> None:
        """Closes the chunk in progress and writes it to disk when FLUSH_S has passed since the last time."""
        if time.monotonic() - self._flushed_at >= FLUSH_S:
            self.flush()

    def flush(self) -> None:
        """Closes the chunk in progress and writes it to disk now."""
        with self._lock:
            if self._finished:
                return
            self._writer.flush()
            if hasattr(self._file, "fileno") and not isinstance(self._file, io.BytesIO):
                os.fsync(self._file.fileno())
            self._flushed_at = time.monotonic()

    def close(self) -> None:
        """Writes what is buffered and closes the file without a summary (another recorder goes on in a new
        part; the reader reads this one up to its last chunk)."""
        self.flush()
        with self._lock:
            if not self._finished:
                self._finished = True
                if not isinstance(self._file, io.BytesIO):
                    self._file.close()

    def finish(self) -> None:
        """Writes the summary and footer and closes the file."""
        with self._lock:
            if self._finished:
                return
            self._finished = True
            self._writer.finish()
            if not isinstance(self._file, io.BytesIO):
                self._file.close()


@dataclass(frozen=True)
class Recorded:
    """One message read back."""

    topic: str
    log_time_ns: int
    data: bytes

    def decode(self) -> Message:
        """The message as its channel's protobuf type."""
        message = channels.MESSAGE_TYPES[self.topic]()
        message.ParseFromString(self.data)
        return message


def _indexed(path: Path, start_ns: int | None, end_ns: int | None) -> list[Recorded] | None:
    """A complete part's messages from start_ns to end_ns through its chunk index (only the chunks in the window
    are read); None when the part has no summary (its recorder is at work, or died)."""
    try:
        with path.open("rb") as stream:
            reader = make_reader(stream)
            summary = reader.get_summary()
            if summary is None or not summary.chunk_indexes:
                return None
            return [Recorded(channel.topic, message.log_time, message.data) for _, channel, message in
                    reader.iter_messages(starting_at=start_ns, ending_at=end_ns, log_time_order=False)
                    if channel.topic in channels.MESSAGE_TYPES]
    except (McapError, EOFError, ValueError, OSError, IndexError, struct.error, zstandard.ZstdError):
        return None


def first_log_ns(root: Path, recording_id: int) -> int | None:
    """The log time of the recording's first message (the replay's zero), read from the parts' summaries."""
    firsts = []
    for path in part_paths(root, recording_id):
        try:
            with path.open("rb") as stream:
                summary = make_reader(stream).get_summary()
            if summary is not None and summary.statistics is not None and summary.statistics.message_count:
                firsts.append(summary.statistics.message_start_time)
                continue
        except (McapError, EOFError, ValueError, OSError, IndexError, struct.error, zstandard.ZstdError):
            pass
        first = next(iter(read_part(path)), None)
        if first is not None:
            firsts.append(first.log_time_ns)
    return min(firsts, default=None)


def read_part(source: Path | IO[bytes]) -> Iterator[Recorded]:
    """The part's messages on known topics, up to its last complete chunk (a cut file ends there, no error)."""
    stream: IO[bytes] = open(source, "rb") if isinstance(source, Path) else source  # noqa: SIM115
    topics: dict[int, str] = {}
    try:
        reader = StreamReader(stream, emit_chunks=True, record_size_limit=256 * 1024 * 1024)
        for record in reader.records:
            inner: Iterable[object] = breakup_chunk(record) if isinstance(record, Chunk) else (record,)
            for item in inner:
                if isinstance(item, Channel):
                    topics[item.id] = item.topic
                elif isinstance(item, McapMessage):
                    topic = topics.get(item.channel_id)
                    if topic in channels.MESSAGE_TYPES:
                        yield Recorded(topic, item.log_time, item.data)
                elif isinstance(item, Schema):
                    continue
    except (McapError, EOFError, ValueError, OSError, IndexError, struct.error, zstandard.ZstdError):
        return  # the cut: everything before it was read
    finally:
        if isinstance(source, Path):
            stream.close()


def read_recording(root: Path, recording_id: int, start_ns: int | None = None,
                   end_ns: int | None = None) -> list[Recorded]:
    """Every part's messages (from start_ns to end_ns when given), in log-time order (a stable sort: one topic's
    order is kept). A sample both recorders wrote at a take-over (a new stream starts with the latest reading) is
    kept once."""
    messages: list[Recorded] = []
    for path in part_paths(root, recording_id):
        indexed = _indexed(path, start_ns, end_ns) if start_ns is not None or end_ns is not None else None
        if indexed is not None:
            messages += indexed
            continue
        messages += [m for m in read_part(path) if (start_ns is None or m.log_time_ns >= start_ns)
                     and (end_ns is None or m.log_time_ns <= end_ns)]
    messages.sort(key=lambda m: m.log_time_ns)
    if len(part_paths(root, recording_id)) < 2:
        return messages
    seen: set[tuple[str, int, bytes]] = set()
    kept: list[Recorded] = []
    for message in messages:
        key = (message.topic, message.log_time_ns, message.data)
        if key not in seen:
            seen.add(key)
            kept.append(message)
    return kept
