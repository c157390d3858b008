"""Audio storage (issue 9, item 4): what is stored, how privately, how much, and what a failure costs."""

import json
import logging
import os
import shutil
import stat
import subprocess
import sys
import wave
from pathlib import Path
from typing import Iterator, List

import numpy as np
import pytest

from fixtures.application import run_application
from fixtures.audio import speak_tones
from fixtures.fakes import SpyRecognizer
from fixtures.paths import ROOT
from fixtures.rig import Rig
from harness.cli import main as harness_main
from speech_event.config import SpeechEventConfig
from speech_event.messages import Float32MultiArray
from speech_event.pipeline.resample import resample
from speech_event.pipeline.storage import INDEX_NAME, StoredUtterance, UtteranceStore, read_index, wav_bytes
from speech_event.ports import Transcript
from speech_event.recognizers.tones import ToneRecognizer


def _stored_rig(folder: Path, recognizer: object = None, **settings: object) -> Rig:
    config = SpeechEventConfig(health_check_period=3600.0, audio_storage_dir=str(folder), **settings)  # type: ignore[arg-type]
    return Rig(config, recognizer or ToneRecognizer())  # type: ignore[arg-type]


def _say(rig: Rig, audio: np.ndarray, rate: int = 48000) -> None:
    for start in range(0, audio.size, 4096):
        rig.clock.advance(4096 / rate)
        rig.sound_detection.publish(Float32MultiArray(data=audio[start : start + 4096]))


@pytest.fixture
def umask() -> Iterator[None]:
    """A umask that would make files world-readable and even take the owner's write bit."""
    old = os.umask(0o222)
    try:
        yield
    finally:
        os.umask(old)


def test_each_utterance_is_a_16_khz_wav_and_an_index_line_with_what_the_node_made_of_it(
    tmp_path: Path,
) -> None:
    folder = tmp_path / "audio"
    rig = _stored_rig(folder)
    speech = speak_tones("yego", 48000)
    _say(rig, speech)
    rig.clock.advance(2.0)
    rig.node.flush_storage()
    assert rig.texts() == ["yego"]
    (line,) = read_index(folder)
    assert line == StoredUtterance(
        file="19700101-000000.085_000001.wav",  # started with its first block, 4096 samples in
        start_time=4096 / 48000,
        duration=speech.size / 48000,
        language="english",
        engine="ToneRecognizer",
        transcript="yego",
        published="yego",
        recognition_time=0.0,  # the rig's stopwatch is the fake clock
    )
    with wave.open(str(folder / line.file)) as wav:
        assert (wav.getnchannels(), wav.getsampwidth(), wav.getframerate()) == (1, 2, 16000)
        pcm = wav.readframes(wav.getnframes())
    assert pcm == wav_bytes(resample(speech, 48000, 16000))
    assert sorted(path.name for path in folder.iterdir()) == [line.file, INDEX_NAME]


def test_utterances_not_published_are_stored_with_published_null(tmp_path: Path) -> None:
    folder = tmp_path / "audio"
    rig = _stored_rig(folder, SpyRecognizer(Transcript("", 1.0)))
    _say(rig, np.full(8192, 0.1, dtype=np.float32))
    rig.clock.advance(2.0)
    rig.node.flush_storage()
    (line,) = read_index(folder)
    assert (line.transcript, line.published, rig.texts()) == ("", None, [])
    assert json.loads((folder / INDEX_NAME).read_text())["published"] is None


def test_files_and_index_are_0600_whatever_the_umask(tmp_path: Path, umask: None) -> None:
    folder = tmp_path / "audio"
    rig = _stored_rig(folder)
    _say(rig, speak_tones("oya", 48000))
    rig.clock.advance(2.0)
    rig.node.flush_storage()
    files = sorted(folder.iterdir())
    assert len(files) == 2
    assert [stat.S_IMODE(path.stat().st_mode) for path in files] == [0o600, 0o600]


def _fill(store: UtteranceStore, count: int, seconds: float) -> None:
    audio = np.full(int(seconds * 48000), 0.25, dtype=np.float32)
    for number in range(1, count + 1):
        store.save(number, float(number), audio, _line)
    store.flush()


def _line(**where: object) -> StoredUtterance:
    return StoredUtterance(
        language="english",
        engine="spy",
        transcript="x",
        published="x",
        recognition_time=0.0,
        **where,  # type: ignore[arg-type]
    )


def test_the_folder_is_kept_under_its_bound_oldest_recordings_first(tmp_path: Path) -> None:
    store = UtteranceStore(str(tmp_path), 48000, max_mb=0.1)  # 104857 bytes: three 1 s recordings
    _fill(store, 5, 1.0)  # each 32044 bytes at 16 kHz
    store.close()
    assert sorted(path.name for path in tmp_path.glob("*.wav")) == [
        "19700101-000003.000_000003.wav",
        "19700101-000004.000_000004.wav",
        "19700101-000005.000_000005.wav",
    ]
    assert sum(path.stat().st_size for path in tmp_path.iterdir()) <= 0.1 * 1024 * 1024
    assert len(read_index(tmp_path)) == 5  # the index remembers the removed ones


def test_a_failed_write_costs_no_transcript_and_warns_at_most_once_a_minute(
    tmp_path: Path, caplog: pytest.LogCaptureFixture
) -> None:
    folder = tmp_path / "audio"
    rig = _stored_rig(folder)
    wall = [0.0]
    rig.node._store._wall_clock = lambda: wall[0]  # type: ignore[union-attr]
    shutil.rmtree(folder)  # removed under the running node
    with caplog.at_level(logging.WARNING, logger="speech_event"):
        for word, after in (("yego", 1.0), ("oya", 1.0), ("ego", 60.0)):
            wall[0] += after
            _say(rig, speak_tones(word, 48000))
            rig.clock.advance(2.0)
            rig.node.flush_storage()
    assert rig.texts() == ["yego", "oya", "ego"]
    messages = [record.getMessage() for record in caplog.records]
    assert len(messages) == 2
    assert messages[0].startswith(
        f"audio storage: cannot write 19700101-000000.085_000001.wav in {folder}: No such file or directory "
        "(1 write(s) failed since the last warning; transcripts are still published"
    )
    assert "(2 write(s) failed since the last warning" in messages[1]


def test_a_folder_that_cannot_be_made_stops_the_node_before_ros_with_one_line(tmp_path: Path) -> None:
    (tmp_path / "a_file").write_text("")
    config = tmp_path / "node.ini"
    config.write_text(f"audio_storage_dir {tmp_path / 'a_file' / 'audio'}\n")
    result = run_application("-c", str(config), "--recognizer", "fake")
    assert result.returncode == 2
    assert result.stderr == (
        f"error: audio_storage_dir {tmp_path / 'a_file' / 'audio'}: cannot store utterances there: "
        "Not a directory; give a folder this user can create and write, or nothing to store no audio\n"
    )


def _store_session(folder: Path, words: List[str]) -> None:
    rig = _stored_rig(folder)
    for word in words:
        _say(rig, speak_tones(word, 48000))
        rig.clock.advance(2.0)
    rig.node.flush_storage()
    assert rig.texts() == words


def test_replay_storage_says_nothing_changed_for_the_same_release(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _store_session(tmp_path, ["yego", "oya"])
    assert harness_main(["replay-storage", str(tmp_path), "--recognizer", "fake"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines[:2]] == ["same", "same"]
    assert lines[0].endswith("  'yego'")
    assert lines[-1] == "2 same, 0 changed, 0 gone"


def test_replay_storage_shows_what_changed_and_exits_1(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _store_session(tmp_path, ["yego", "oya", "ego"])
    lines = (tmp_path / INDEX_NAME).read_text().splitlines()
    edited = json.loads(lines[1])
    edited["published"] = "ok"  # as if the release that stored it had heard "ok"
    lines[1] = json.dumps(edited)
    (tmp_path / INDEX_NAME).write_text("\n".join(lines) + "\n")
    (tmp_path / json.loads(lines[2])["file"]).unlink()
    assert harness_main(["replay-storage", str(tmp_path), "--recognizer", "fake"]) == 1
    out = capsys.readouterr().out.splitlines()
    assert out[1] == f"changed  {edited['file']}  'ok' -> 'oya'"
    assert out[2].startswith("gone     ")
    assert out[-1] == "1 same, 1 changed, 1 gone"


def test_replay_storage_of_a_folder_without_an_index_is_one_clear_error(tmp_path: Path) -> None:
    result = subprocess.run(
        [sys.executable, "-m", "harness", "replay-storage", str(tmp_path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
    )
    assert (result.returncode, result.stderr) == (
        2,
        f"error: {tmp_path}: no index.jsonl; give a folder the node stored utterances in\n",
    )
