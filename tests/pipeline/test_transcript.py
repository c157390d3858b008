"""Step 5: which engine answers are transcripts, and what is published for each."""

import logging
import math
from typing import Optional

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from speech_event.config import SpeechEventConfig
from speech_event.pipeline.transcript import checked_transcript, proper_transcript, styled, text_to_publish
from speech_event.ports import Transcript
from speech_event.topics import SPEECH_NOT_RECOGNIZED


@pytest.mark.parametrize(
    ("answer", "shown"),
    [
        ("go to the kitchen", "'go to the kitchen'"),
        (None, "None"),
        (Transcript(b"go"), "Transcript(text=b'go', confidence=None, rejected=None)"),  # type: ignore[arg-type]
    ],
)
def test_an_answer_that_is_not_a_transcript_with_text_is_refused_naming_it(
    answer: object, shown: str
) -> None:
    with pytest.raises(ValueError) as error:
        checked_transcript(answer, 3)
    assert str(error.value) == f"the engine answered {shown}, not a Transcript with text"


@given(confidence=st.one_of(st.none(), st.floats(0.0, 1.0)))
def test_a_transcript_without_confidence_or_with_one_from_0_to_1_is_kept_as_it_is(
    confidence: Optional[float],
) -> None:
    transcript = Transcript("go to the kitchen", confidence)
    assert checked_transcript(transcript, 1) == transcript


@pytest.mark.parametrize("confidence", [-0.1, 1.5, math.inf, "0.9", True, [0.5]])
def test_a_confidence_that_is_not_a_number_from_0_to_1_is_refused(confidence: object) -> None:
    with pytest.raises(ValueError) as error:
        checked_transcript(Transcript("go", confidence), 2)  # type: ignore[arg-type]
    assert str(error.value) == (
        f"the engine reported confidence {confidence!r}; allowed: a number from 0 to 1 or none"
    )


@pytest.mark.parametrize("nan", [math.nan, np.float32("nan")])
def test_a_nan_confidence_keeps_the_text_as_unscored_with_a_warning(
    nan: float, caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.WARNING, logger="speech_event"):
        assert checked_transcript(Transcript("go to the kitchen", nan), 7) == Transcript("go to the kitchen")
    assert [(record.levelno, record.getMessage()) for record in caplog.records] == [
        (logging.WARNING, "utterance 7: the engine reported confidence NaN; taken as no confidence reported")
    ]


@pytest.mark.parametrize(
    ("answer", "taken"),
    [
        (Transcript("go", 0.5), Transcript("go", 0.5)),
        (Transcript("go", 0.0), Transcript("go", 0.0)),  # both ends of [0, 1] are confidences
        (Transcript("go", 1.0), Transcript("go", 1.0)),
        (Transcript("", rejected="stop"), Transcript("", rejected="stop")),
        (Transcript("go", math.nan), Transcript("go")),
        (None, None),
        ("go", None),
        (Transcript(None), None),  # type: ignore[arg-type]
        (Transcript("go", 1.5), None),
        (Transcript("go", "high"), None),  # type: ignore[arg-type]
    ],
)
def test_speculations_and_partials_take_an_answer_as_the_final_recognition_does_without_a_word(
    answer: object, taken: Optional[Transcript], caplog: pytest.LogCaptureFixture
) -> None:
    with caplog.at_level(logging.DEBUG, logger="speech_event"):
        assert proper_transcript(answer) == taken
    assert caplog.records == []


@pytest.mark.parametrize(
    ("written", "robot"),
    [
        (" Yes.", "yes"),
        ("No, thank you.", "no thank you"),
        ("GO!", "go"),
        ("I'm not sure...", "i'm not sure"),
        ("'Hello,' she said.", "hello she said"),
        ("10 of clubs.", "ten of clubs"),
        ("It costs 1,250 francs.", "it costs one thousand two hundred fifty francs"),
        ("Twenty-one  guns", "twenty one guns"),
        ("Un café, s'il vous plaît.", "un café s'il vous plaît"),
        ("Muraho, amakuru?", "muraho amakuru"),
        ("...", ""),
    ],
)
def test_free_speech_is_written_as_the_robots_model_writes_unless_the_engines_writing_is_asked_for(
    written: str, robot: str
) -> None:
    assert styled(written, "robot") == robot
    assert styled(written, "engine") == written.strip()
    engine = SpeechEventConfig(text_style="engine")
    assert text_to_publish(Transcript(written), SpeechEventConfig(), phrase=False) == (robot or None)
    assert text_to_publish(Transcript(written), engine, phrase=False) == written.strip()


def test_a_grammars_phrase_is_published_as_the_grammar_spells_it() -> None:
    assert text_to_publish(Transcript("Thank You"), SpeechEventConfig(), phrase=True) == "Thank You"


def test_the_published_text_is_stripped() -> None:
    assert (
        text_to_publish(Transcript("  go to the kitchen \n"), SpeechEventConfig(), phrase=False)
        == "go to the kitchen"
    )


def test_a_confidence_at_the_threshold_is_published_and_one_below_is_not() -> None:
    config = SpeechEventConfig(confidence=0.5, publish_unrecognized=True)
    assert text_to_publish(Transcript("go", 0.5), config, phrase=False) == "go"
    assert text_to_publish(Transcript("go", 0.49), config, phrase=False) == SPEECH_NOT_RECOGNIZED
    assert (
        text_to_publish(Transcript("go"), config, phrase=False) == "go"
    )  # no confidence reported: not judged


@given(
    text=st.sampled_from(["", " ", "\n\t "]),
    confidence=st.one_of(st.none(), st.floats(0.0, 1.0)),
    publish_unrecognized=st.booleans(),
)
def test_an_empty_transcript_publishes_the_error_text_or_nothing_whatever_its_confidence(
    text: str, confidence: Optional[float], publish_unrecognized: bool
) -> None:
    config = SpeechEventConfig(publish_unrecognized=publish_unrecognized)
    expected = SPEECH_NOT_RECOGNIZED if publish_unrecognized else None
    assert text_to_publish(Transcript(text, confidence), config, phrase=False) == expected


@given(confidence=st.floats(0.0, 1.0, exclude_max=True), publish_unrecognized=st.booleans())
def test_a_transcript_below_the_confidence_threshold_publishes_the_error_text_or_nothing(
    confidence: float, publish_unrecognized: bool
) -> None:
    config = SpeechEventConfig(confidence=1.0, publish_unrecognized=publish_unrecognized)
    expected = SPEECH_NOT_RECOGNIZED if publish_unrecognized else None
    assert text_to_publish(Transcript("go to the kitchen", confidence), config, phrase=False) == expected
