"""What is not speech: utterances shorter than min_utterance_length, or below vad_threshold (Silero VAD)."""

import numpy as np
import pytest

from fixtures.audio import noise
from fixtures.tts import speak_tts
from speech_event.pipeline.screen import Discard, SpeechScreen
from speech_event.pipeline.vad import SileroVad, silero_model_path


@pytest.fixture(scope="module")
def vad() -> SileroVad:
    return SileroVad(silero_model_path())


def test_silero_vad_hears_speech_and_not_noise_or_silence(vad: SileroVad) -> None:
    rng = np.random.default_rng(0)
    assert vad.max_speech_probability(speak_tts("go to the kitchen", 16000)) > 0.9
    assert vad.max_speech_probability(noise(16000, -30.0, rng)) < 0.2
    assert vad.max_speech_probability(np.zeros(16000, dtype=np.float32)) < 0.05
    assert vad.max_speech_probability(np.zeros(511, dtype=np.float32)) == 0.0  # shorter than a window


def test_the_screen_drops_short_utterances_at_the_exact_length() -> None:
    screen = SpeechScreen(0.5, 0.0, None)
    assert screen.discard(np.zeros(7999, dtype=np.float32), 16000) is Discard.TOO_SHORT
    assert screen.discard(np.zeros(8000, dtype=np.float32), 16000) is None


def test_the_screen_asks_the_vad_at_16_khz_and_compares_with_the_threshold() -> None:
    heard = []

    def probability(audio: np.ndarray) -> float:
        heard.append(audio.size)
        return 0.5

    assert SpeechScreen(0.0, 0.5, probability).discard(np.zeros(48000, np.float32), 48000) is None
    assert SpeechScreen(0.0, 0.51, probability).discard(np.zeros(16000, np.float32), 16000) is (
        Discard.BELOW_VAD_THRESHOLD
    )
    assert heard == [16000, 16000]  # 1 s at 48 kHz resampled to 16 kHz
