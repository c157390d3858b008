"""Step 5 of the pipeline: what, if anything, to publish for one transcript."""

import logging
import math
import numbers
from typing import Optional

from speech_event.config import SpeechEventConfig
from speech_event.ports import Transcript
from speech_event.topics import SPEECH_NOT_RECOGNIZED

_LOG = logging.getLogger("speech_event")


def checked_transcript(result: object, number: int) -> Transcript:
    """The engine's answer for utterance ``number`` if it is a proper transcript; ValueError if not.

    A NaN confidence counts as none reported (the text is published, with a warning): an engine
    that cannot score must not silently lose what it heard.
    """
    if not isinstance(result, Transcript) or not isinstance(result.text, str):
        raise ValueError(f"the engine answered {result!r}, not a Transcript with text")
    confidence = result.confidence
    if confidence is None:
        return result
    real = isinstance(confidence, numbers.Real) and not isinstance(confidence, bool)
    if real and math.isnan(float(confidence)):
        _LOG.warning(
            "utterance %d: the engine reported confidence NaN; taken as no confidence reported", number
        )
        return Transcript(result.text)
    if not real or not 0 <= float(confidence) <= 1:
        raise ValueError(
            f"the engine reported confidence {confidence!r}; allowed: a number from 0 to 1 or none"
        )
    return result


def text_to_publish(transcript: Transcript, config: SpeechEventConfig) -> Optional[str]:
    """The stripped text; for an empty or low-confidence one, the error text or nothing."""
    text = transcript.text.strip()
    confident = transcript.confidence is None or transcript.confidence >= config.confidence
    if text and confident:
        return text
    return SPEECH_NOT_RECOGNIZED if config.publish_unrecognized else None
