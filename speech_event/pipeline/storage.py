"""Keeps each utterance for replay (``audio_storage_dir``): a 16 kHz 16-bit WAV and an index line.

A field team replays a day of stored utterances against a new release (``python -m harness
replay-storage DIR``), so each utterance is stored with what the node made of it: one JSON line per
utterance in ``index.jsonl``. Storing never costs a transcript: the node publishes first and hands
the utterance to this store's own thread; a full disk, a removed folder or any other write error is
one warning (at most one a minute, with the count since) and the node goes on. Files are made 0600
whatever the umask (recordings of people speaking), and the folder is kept under
``audio_storage_max_mb``, the oldest recordings removed first.
"""

import dataclasses
import json
import logging
import os
import queue
import threading
import time
import wave
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO, Callable, List, Optional, Tuple

import numpy as np

from speech_event.config import SpeechEventConfig
from speech_event.errors import StorageError
from speech_event.pipeline.resample import resample

_LOG = logging.getLogger("speech_event")

INDEX_NAME = "index.jsonl"
STORED_RATE = 16000
PRIVATE = 0o600
WARNING_INTERVAL = 60.0  # seconds between two warnings about failed writes


@dataclass(frozen=True)
class StoredUtterance:
    """One line of the index: what was heard and what the node made of it."""

    file: str  # the WAV's name, in the same folder
    start_time: float  # the node's clock (ROS time on the robot) when its first block arrived
    duration: float  # seconds of audio
    language: str
    engine: str
    transcript: str  # what the engine said ("" when it failed)
    published: Optional[str]  # what the node published for it; None: nothing (discarded, confidence)
    recognition_time: float  # seconds the engine took


def read_index(directory: Path) -> List[StoredUtterance]:
    """The lines of ``directory``'s index.jsonl, in the order they were written."""
    lines = (directory / INDEX_NAME).read_text(encoding="utf-8").splitlines()
    return [StoredUtterance(**json.loads(line)) for line in lines if line.strip()]


def check_storage_dir(directory: str) -> None:
    """Make the folder (0700) and prove a file can be written in it; StorageError says why not."""
    path = Path(directory)
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
        probe = path / f".write_test_{os.getpid()}"
        _private_file(probe, os.O_WRONLY | os.O_CREAT | os.O_TRUNC).close()
        probe.unlink()
    except OSError as problem:
        raise StorageError(
            f"audio_storage_dir {directory}: cannot store utterances there: "
            f"{problem.strerror or problem}; give a folder this user can create and write, or "
            "nothing to store no audio"
        ) from None


def _private_file(path: Path, flags: int) -> BinaryIO:
    descriptor = os.open(path, flags, PRIVATE)
    os.fchmod(descriptor, PRIVATE)  # the umask may have taken bits off; a file made before too
    return os.fdopen(descriptor, "wb", buffering=0)


def wav_bytes(audio: np.ndarray) -> bytes:
    """Audio in [-1, 1] as 16-bit little-endian PCM samples (clipped to that range)."""
    return np.asarray(np.round(np.clip(audio, -1.0, 1.0) * 32767.0), dtype="<i2").tobytes()


def store_for(config: SpeechEventConfig) -> "Optional[UtteranceStore]":
    """The store audio_storage_dir asks for, or None when storing is off."""
    if not config.audio_storage_dir:
        return None
    return UtteranceStore(config.audio_storage_dir, config.sample_rate, config.audio_storage_max_mb)


class UtteranceStore:
    """Writes utterances on a thread of its own, in the order they were handed over."""

    def __init__(
        self,
        directory: str,
        sample_rate: int,
        max_mb: float,
        wall_clock: Callable[[], float] = time.monotonic,
    ) -> None:
        check_storage_dir(directory)
        self._directory = Path(directory)
        self._sample_rate = sample_rate
        self._max_bytes = int(max_mb * 1024 * 1024)
        self._wall_clock = wall_clock
        self._pending: queue.Queue[Optional[Tuple[StoredUtterance, np.ndarray]]] = queue.Queue()  # novermin
        self._last_warning: Optional[float] = None
        self.failures = 0  # writes that failed, since start
        self._failed_since_warning = 0
        self._writer = threading.Thread(target=self._write_all, name="speech_event_storage", daemon=True)
        self._writer.start()

    def save(
        self,
        number: int,
        started_at: float,
        audio: np.ndarray,
        describe: Callable[..., StoredUtterance],
    ) -> None:
        """Hand utterance ``number`` over; ``describe(file=, start_time=, duration=)`` is its index
        line. Its file is named by the time it started (UTC) and its number."""
        stamp = time.strftime("%Y%m%d-%H%M%S", time.gmtime(started_at))
        name = f"{stamp}.{int(started_at * 1000) % 1000:03d}_{number:06d}.wav"
        line = describe(file=name, start_time=started_at, duration=audio.size / self._sample_rate)
        self._pending.put((line, audio))

    def flush(self) -> None:
        """Wait until everything handed over so far is written (or has failed)."""
        self._pending.join()

    def close(self) -> None:
        self._pending.put(None)
        self._writer.join()

    def _write_all(self) -> None:
        while True:
            item = self._pending.get()
            try:
                if item is None:
                    return
                self._write(*item)
            finally:
                self._pending.task_done()

    def _write(self, line: StoredUtterance, audio: np.ndarray) -> None:
        try:
            pcm = wav_bytes(resample(audio.astype(np.float32), self._sample_rate, STORED_RATE))
            recording = self._directory / line.file
            with _private_file(recording, os.O_WRONLY | os.O_CREAT | os.O_TRUNC) as out, wave.open(
                out, "wb"
            ) as wav:
                wav.setnchannels(1)
                wav.setsampwidth(2)
                wav.setframerate(STORED_RATE)
                wav.writeframes(pcm)
            record = (json.dumps(dataclasses.asdict(line), ensure_ascii=False) + "\n").encode("utf-8")
            with _private_file(self._directory / INDEX_NAME, os.O_WRONLY | os.O_CREAT | os.O_APPEND) as index:
                index.write(record)
            self._keep_within_bound()
        except OSError as problem:
            self._failed(line.file, problem)

    def _keep_within_bound(self) -> None:
        """Remove the oldest recordings (by name: time, then sequence) until the folder fits."""
        recordings = sorted(self._directory.glob("*.wav"))
        total = (
            sum(path.stat().st_size for path in recordings) + (self._directory / INDEX_NAME).stat().st_size
        )
        for oldest in recordings[:-1]:  # the newest stays, whatever its size
            if total <= self._max_bytes:
                break
            total -= oldest.stat().st_size
            oldest.unlink()

    def _failed(self, name: str, problem: OSError) -> None:
        self.failures += 1
        self._failed_since_warning += 1
        now = self._wall_clock()
        if self._last_warning is not None and now - self._last_warning < WARNING_INTERVAL:
            return
        _LOG.warning(
            "audio storage: cannot write %s in %s: %s (%d write(s) failed since the last warning; "
            "transcripts are still published; next warning in %.0f s at the earliest)",
            name,
            self._directory,
            problem.strerror or problem,
            self._failed_since_warning,
            WARNING_INTERVAL,
        )
        self._last_warning = now
        self._failed_since_warning = 0
