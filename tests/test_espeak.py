"""The tts voice and the word timings: the same samples for the same text, whatever came before
(issue 17, item 1)."""

import hashlib
import subprocess
import sys
from pathlib import Path

import pytest

from fixtures.espeak import ESPEAK_DEFAULT, PYTTSX3, EspeakError, synthesise
from fixtures.tts import speak_tts, speak_with_word_starts

ROOT = Path(__file__).resolve().parents[1]
PHRASE = "bring me the red cup"  # in no other test, so nothing has spoken it in this process yet


def _digest_in_a_fresh_process(text: str) -> str:
    code = (
        "import hashlib, sys; from fixtures.tts import speak_tts; "
        "print(hashlib.sha1(speak_tts(sys.argv[1], 48000).tobytes()).hexdigest())"
    )
    return subprocess.run(
        [sys.executable, "-c", code, text], cwd=ROOT, capture_output=True, text=True, check=True
    ).stdout.strip()


def test_the_tts_voice_after_word_timings_is_the_voice_of_a_fresh_process() -> None:
    # The failure on a new machine: once the word timings had set espeak-ng up, the tts voice
    # wrote no audio at all.
    speak_with_word_starts("go to the kitchen and stop", 48000)
    after = hashlib.sha1(speak_tts(PHRASE, 48000).tobytes()).hexdigest()
    assert after == _digest_in_a_fresh_process(PHRASE)


def test_a_text_gives_the_same_samples_whatever_was_spoken_before() -> None:
    # In one espeak-ng process the second "open the door" differed from the first (its pitch
    # flutter counter runs on); each phrase now has a process of its own.
    first = synthesise("open the door", ESPEAK_DEFAULT)
    synthesise("open the door", PYTTSX3)
    synthesise("close the window", ESPEAK_DEFAULT)
    again = synthesise("open the door", ESPEAK_DEFAULT)
    assert again == first
    assert len(first[1]) == 3 and list(first[1]) == sorted(first[1])


@pytest.mark.parametrize("text", ["", "   "])
def test_a_text_with_nothing_to_say_is_named_in_the_error(text: str) -> None:
    with pytest.raises(EspeakError) as raised:
        synthesise(text, PYTTSX3)
    assert (
        str(raised.value) == f"espeak-ng gave no audio but silence for {text!r}: nothing in it to pronounce"
    )
