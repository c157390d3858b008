"""Step 7 of the pipeline: what, if anything, to publish for one transcript, and how it is written."""

import logging
import math
import numbers
from typing import Optional, Union

from speech_event.config import SpeechEventConfig
from speech_event.ports import Transcript
from speech_event.spelling import robot_written
from speech_event.topics import SPEECH_NOT_RECOGNIZED

_LOG = logging.getLogger("speech_event")


def checked_transcript(result: object, number: int) -> Transcript:
    """The engine's answer for utterance ``number`` if it is a proper transcript; ValueError if not.

    A NaN confidence counts as none reported (the text is published, with a warning): an engine
    that cannot score must not silently lose what it heard.
    """
    judged = _judged(result)
    if isinstance(judged, str):
        raise ValueError(judged)
    if judged is not result:
        _LOG.warning(
            "utterance %d: the engine reported confidence NaN; taken as no confidence reported", number
        )
    return judged


def proper_transcript(result: object) -> Optional[Transcript]:
    """The engine's answer as ``checked_transcript`` takes it, or None where that fails, without a
    word: speculations and partial texts judge answers by it, so a broken engine's answer is a
    failed recognition there too (never a complete answer, never an exception), and the final
    recognition alone says why."""
    judged = _judged(result)
    return None if isinstance(judged, str) else judged


def _judged(result: object) -> Union[Transcript, str]:
    """The transcript to take from an engine's answer (itself, or without a NaN confidence), or
    why it is none."""
    if not isinstance(result, Transcript) or not isinstance(result.text, str):
        return f"the engine answered {result!r}, not a Transcript with text"
    confidence = result.confidence
    if confidence is None:
        return result
    real = isinstance(confidence, numbers.Real) and not isinstance(confidence, bool)
    if real and math.isnan(float(confidence)):
        return Transcript(result.text)
    if not real or not 0 <= float(confidence) <= 1:
        return f"the engine reported confidence {confidence!r}; allowed: a number from 0 to 1 or none"
    return result


def text_to_publish(transcript: Transcript, config: SpeechEventConfig, phrase: bool) -> Optional[str]:
    """The text as ``config.text_style`` writes it (a grammar's ``phrase`` as the grammar spells
    it); for an empty or low-confidence one, the error text or nothing."""
    text = transcript.text.strip() if phrase else styled(transcript.text, config.text_style)
    confident = transcript.confidence is None or transcript.confidence >= config.confidence
    if text and confident:
        return text
    return SPEECH_NOT_RECOGNIZED if config.publish_unrecognized else None


def styled(text: str, style: str) -> str:
    """A free-speech ``text`` as the text_style ``style`` writes it: ``robot``, as the robot's NeMo
    model writes (speech_event/spelling.py), or ``engine``, as the engine wrote it (stripped)."""
    return robot_written(text) if style == "robot" else text.strip()
