"""Step 5 of the pipeline: what, if anything, to publish for one transcript."""

from typing import Optional

from speech_event import SPEECH_NOT_RECOGNIZED
from speech_event.config import SpeechEventConfig
from speech_event.ports import Transcript


def text_to_publish(transcript: Transcript, config: SpeechEventConfig) -> Optional[str]:
    """The stripped text; for an empty or low-confidence one, the error text or nothing."""
    text = transcript.text.strip()
    confident = transcript.confidence is None or transcript.confidence >= config.confidence
    if text and confident:
        return text
    return SPEECH_NOT_RECOGNIZED if config.publish_unrecognized else None
