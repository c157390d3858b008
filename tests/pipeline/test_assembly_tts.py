"""The length cut on real synthetic speech: it never falls inside a word.

espeak-ng says where each word starts (fixtures/tts.py). 22 long utterances, each two
sentences joined with "and" (9 to 11 s), are assembled with an 8 s limit, so each is cut once
(the search: the 2.4 s before the limit). A cut is between words when the 20 ms around it are
silent (espeak-ng's pauses, under the tts voice's -55 dBFS noise) or it is within 30 ms of a
word's start. The previous cut (the latest dip within 2x of the quietest in the last second)
fell inside a word in 4 of these 22.
"""

from typing import List

import numpy as np
import pytest

from fixtures.tts import speak_with_word_starts
from speech_event.pipeline.assembly import UtteranceAssembler

RATE = 48000
LIMIT_SECONDS = 8.0
SILENT_DBFS = -50.0
NEAR_A_WORD_START = 0.03
SENTENCES = [
    "tonight the robot will guide our visitors through the museum and tell them about every painting on the wall",
    "the construction of the new library started last spring and the builders hope to finish it before the rainy season",
    "please remember to close the windows in the kitchen before you leave the house this afternoon",
    "my grandmother told me many stories about the village where she grew up near the great lake",
    "the children were playing football in the garden while their parents prepared dinner for everyone",
    "could you bring me the blue folder from the office upstairs and put it on the table by the door",
    "every morning the farmer walks to the market with fresh vegetables and sells them to his neighbours",
    "the weather forecast says that it will rain heavily tomorrow so take an umbrella with you",
    "we visited the national park during the holidays and saw elephants giraffes and many beautiful birds",
    "the teacher explained the lesson slowly so that all the students could understand the difficult parts",
    "after the meeting the manager thanked everybody for their hard work and announced a new project",
    "the train to the capital leaves at seven o'clock and arrives a little after noon on weekdays",
    "i would like to order two cups of coffee a glass of orange juice and a piece of chocolate cake",
    "the doctor asked the patient to come back next week for another examination and some blood tests",
    "our team practised every evening for three months before the championship in the neighbouring country",
    "the old bridge over the river was repaired last year and now cars and buses can cross it again",
    "she opened the letter carefully read it twice and then smiled because it contained wonderful news",
    "the museum guide showed us ancient tools pottery and jewellery that were found in the northern hills",
    "when the power went out the whole neighbourhood gathered outside to talk and look at the stars",
    "the scientists measured the temperature of the water every hour for a whole week during the experiment",
    "the robot answered every question politely and then invited the visitors to follow it to the next room",
    "my brother studies engineering at the university and wants to build bridges roads and railways one day",
]
LONG = [SENTENCES[i] + " and " + SENTENCES[(i + 7) % len(SENTENCES)] for i in range(len(SENTENCES))]


def _level_dbfs(audio: np.ndarray, at: int) -> float:
    around = audio[max(0, at - RATE // 100) : at + RATE // 100].astype(np.float64)
    return float(20 * np.log10(np.sqrt(np.mean(np.square(around))) + 1e-12))


@pytest.mark.parametrize("text", LONG, ids=[f"sentences_{i}" for i in range(len(LONG))])
def test_a_long_utterance_is_cut_between_words(text: str) -> None:
    audio, word_starts = speak_with_word_starts(text, RATE)
    assert audio.size > LIMIT_SECONDS * RATE  # long enough to be cut
    cuts: List[int] = []
    for utterance in UtteranceAssembler(RATE, LIMIT_SECONDS).add(audio):
        cuts.append((cuts[-1] if cuts else 0) + utterance.size)
    assert cuts
    for cut in cuts:
        nearest = min(abs(cut / RATE - start) for start in word_starts[1:])
        level = _level_dbfs(audio, cut)
        assert level <= SILENT_DBFS or nearest <= NEAR_A_WORD_START, (
            f"cut at {cut / RATE:.3f} s: {level:.0f} dBFS, {nearest * 1000:.0f} ms from a word start"
        )
