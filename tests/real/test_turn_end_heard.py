"""Free speech with turn_end_model smart-turn (what auto, the default, chooses with Whisper in
English), on trained weights (Whisper tiny.en) and LJ Speech's readings: the turn ends at the end of
speech when both the text and Smart Turn say it is complete, and waits for the pause when the audio
says the reader is not done, whatever Whisper writes; the same audio gives the same texts however
long the engine takes (the node holds the blocks that come while a decision is pending)."""

from typing import Any, Dict, List, Tuple

import pytest

from fixtures.paths import ROOT
from fixtures.recordings import LJSPEECH
from harness.memory_runner import run_in_memory
from harness.scenario import parse_scenario
from speech_event.config import SpeechEventConfig

PAUSE = 1.5  # speech_pause_period


def published(
    steps: List[Dict[str, Any]], config: Dict[str, Any], recognition_seconds: float = 0.0
) -> List[Tuple[float, str]]:
    """What the node publishes for ``steps`` in free speech on tiny.en, with its scenario times."""
    document = {
        "name": "turn end",
        "recognizer": "whisper-tiny.en",
        "config": {"partial_period": 0.0, **config},
        "steps": steps,
        "expect": {"published": []},
    }
    scenario = parse_scenario(document, str(ROOT / "turn_end.toml"), SpeechEventConfig())
    return [(item.time, item.text) for item in run_in_memory(scenario, recognition_seconds).published]


def reading(stem: str) -> Dict[str, Any]:
    return {"play": str(LJSPEECH / f"{stem}.wav")}


SMART_TURN = {"turn_end_model": "smart-turn"}
PAUSE_ONLY = {"turn_end_model": "none"}
TEXT_ALONE = {"end_of_speech": 0.3, "turn_end_model": "none"}


def test_a_reading_that_ends_a_sentence_is_published_at_the_end_of_speech_not_after_the_pause() -> None:
    steps = [reading("LJ001-0002"), {"silence": 3.0}]
    [(heard_at, heard)] = published(steps, SMART_TURN)
    [(paused_at, paused)] = published(steps, PAUSE_ONLY)
    assert heard == paused
    # the pause ends 1.5 s after the last block; the end of speech 0.3 s after it, decided then
    assert paused_at - heard_at > PAUSE - 0.5
    # left to its default (auto), Smart Turn hears with Whisper in English
    assert published(steps, {}) == [(heard_at, heard)]


def test_a_reading_that_stops_mid_sentence_waits_for_the_pause_with_smart_turn_but_not_on_its_text_alone() -> (
    None
):
    # LJ001-0004 stops mid-sentence (Smart Turn: 0.01), and Whisper closes it with a period anyway
    steps = [reading("LJ001-0004"), {"silence": 3.0}]
    [(heard_at, heard)] = published(steps, SMART_TURN)
    [(paused_at, paused)] = published(steps, PAUSE_ONLY)
    [(text_at, text)] = published(steps, TEXT_ALONE)
    assert heard == paused == text
    assert heard_at == paused_at
    assert paused_at - text_at > PAUSE - 0.5


def test_a_reader_who_pauses_mid_sentence_is_not_cut_off_where_the_text_alone_would_cut() -> None:
    # the first reading stops mid-sentence, and the second goes on after half a second
    steps = [reading("LJ001-0004"), {"silence": 0.5}, reading("LJ001-0002"), {"silence": 3.0}]
    assert len(published(steps, SMART_TURN)) == 1
    assert len(published(steps, TEXT_ALONE)) == 2


@pytest.mark.parametrize("recognition_seconds", [0.5, 2.0])
def test_the_same_audio_gives_the_same_texts_at_the_same_ends_however_slow_the_engine(
    recognition_seconds: float,
) -> None:
    steps = [
        reading("LJ001-0004"),
        {"silence": 0.5},
        reading("LJ001-0002"),
        {"silence": 3.0},
        reading("LJ001-0008"),
        {"silence": 3.0},
    ]
    quick = published(steps, SMART_TURN)
    slow = published(steps, SMART_TURN, recognition_seconds)
    assert [text for _, text in slow] == [text for _, text in quick]
    assert len(quick) == 2


def test_with_the_audio_alone_deciding_smart_turn_ends_the_sentence_and_waits_mid_sentence() -> None:
    audio_alone = {**SMART_TURN, "turn_end_text": False}
    # (LJ001-0002 it cuts after its first two words, "in being": the text rule is what stops that)
    for stem, ends_early in (("LJ001-0008", True), ("LJ001-0004", False)):
        steps = [reading(stem), {"silence": 3.0}]
        [(heard_at, heard)] = published(steps, audio_alone)
        [(paused_at, paused)] = published(steps, PAUSE_ONLY)
        assert heard == paused
        assert (paused_at - heard_at > PAUSE - 0.5) == ends_early, stem
