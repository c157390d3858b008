"""The tones code and the fake recognizer that reads it.

A stand-in for speech in hermetic tests: each character of ``[a-z']`` is a short pure tone of its
own frequency, letters are parted by a short gap and words by a long one. The fake recognizer
decodes it back exactly, so a node test can assert the text published for the text "spoken".
The alphabet is the Kinyarwanda model's, without the space (a space is a long gap).

With a grammar in force it answers with the decoded text when that is a phrase of the grammar, and
otherwise with nothing, naming the phrase nearest in spelling as rejected: the node's grammar
handling can be tested with it as with the real engines.
"""

import difflib
from typing import List, Optional

import numpy as np

from speech_event.grammar import Grammar
from speech_event.ports import Transcript

SYMBOLS = "abcdefghijklmnopqrstuvwxyz'"
LOWEST_HZ = 400.0
STEP_HZ = 100.0
TONE_SECONDS = 0.03
LETTER_GAP_SECONDS = 0.015
WORD_GAP_SECONDS = 0.09
AMPLITUDE = 0.5

# Decoding: 2.5 ms frames; a frame is sound when its RMS is over the threshold (-20 dBFS, far above
# the -40 dBFS noise the code must survive and far below a tone's -9 dBFS).
_FRAME_SECONDS = 0.0025
_SOUND_RMS = 0.1
_SHORTEST_TONE_SECONDS = 0.01
_WORD_GAP_THRESHOLD_SECONDS = (LETTER_GAP_SECONDS + WORD_GAP_SECONDS) / 2
_FFT_SIZE = 8192


def symbol_frequency(symbol: str) -> float:
    """The frequency, in Hz, of one symbol's tone."""
    return LOWEST_HZ + STEP_HZ * SYMBOLS.index(symbol)


def _sound_runs(audio: np.ndarray, frame: int) -> List[range]:
    """Runs of consecutive sound frames, as frame index ranges."""
    frames = audio[: audio.size // frame * frame].reshape(-1, frame).astype(np.float64)
    sound = np.sqrt(np.mean(np.square(frames), axis=1)) > _SOUND_RMS
    edges = np.flatnonzero(np.diff(np.concatenate(([0], sound.astype(np.int8), [0]))))
    return [range(start, stop) for start, stop in zip(edges[::2], edges[1::2])]


def _symbol_of(tone: np.ndarray, sample_rate: int) -> str:
    spectrum = np.abs(np.fft.rfft(tone * np.hanning(tone.size), _FFT_SIZE))
    peak_hz = float(np.argmax(spectrum)) * sample_rate / _FFT_SIZE
    index = round((peak_hz - LOWEST_HZ) / STEP_HZ)
    if 0 <= index < len(SYMBOLS) and abs(peak_hz - symbol_frequency(SYMBOLS[index])) < STEP_HZ / 3:
        return SYMBOLS[index]
    return ""  # a burst of sound that is no symbol of the code


def decode_tones(audio: np.ndarray, sample_rate: int) -> str:
    """The text tones-code ``audio`` spells; bursts of sound that are no symbol are skipped."""
    frame = max(1, int(_FRAME_SECONDS * sample_rate))
    shortest = _SHORTEST_TONE_SECONDS * sample_rate / frame
    word_gap = _WORD_GAP_THRESHOLD_SECONDS * sample_rate / frame
    text: List[str] = []
    previous_stop = None
    for run in _sound_runs(audio, frame):
        if len(run) < shortest:
            continue
        # Leave out the edge frames: there the tone ramps up and down.
        tone = audio[(run.start + 1) * frame : (run.stop - 1) * frame]
        symbol = _symbol_of(tone, sample_rate)
        if not symbol:
            continue
        if previous_stop is not None and run.start - previous_stop > word_gap:
            text.append(" ")
        text.append(symbol)
        previous_stop = run.stop
    return "".join(text)


class ToneRecognizer:
    """The fake recognizer: decodes the tones code, reports no confidence; takes a grammar."""

    sample_rate = 16000

    def __init__(self, grammar: Optional[Grammar] = None) -> None:
        self._phrases: Optional[List[str]] = None
        if grammar is not None:
            self.use_grammar(grammar)

    def check_grammar(self, grammar: Grammar) -> None:
        """Any grammar of at most MAX_SENTENCES sentences: the answer is matched against them."""
        grammar.sentences("the tones engine")

    def use_grammar(self, grammar: Optional[Grammar]) -> None:
        self._phrases = None if grammar is None else list(grammar.sentences("the tones engine"))

    def transcribe(self, audio: np.ndarray) -> Transcript:
        text = decode_tones(audio, self.sample_rate)
        if self._phrases is None or not text or text in self._phrases:
            return Transcript(text)
        nearest = max(self._phrases, key=lambda phrase: difflib.SequenceMatcher(None, text, phrase).ratio())
        return Transcript("", rejected=nearest)

    def stop(self) -> None:
        """Nothing to stop: decoding takes a few milliseconds (so speculation may use this engine)."""
