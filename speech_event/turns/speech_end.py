"""Where the speech in the utterance so far ended, heard in its samples (issue 44).

soundDetection's driver sends a second of room sound after speech, and in a noisy room the robot's
lenient gate passes noise blocks: blocks keep coming after the last word, so no pause in their
arrival tells the end. This finds it in the audio: 20 ms frames from the utterance's first sample,
their energies averaged over 100 ms (room noise fluctuates less so); a frame is speech when that
is 6 dB above the utterance's floor (its 10th percentile: stationary room noise stays under it)
and within 30 dB of the loudest frame heard from this speaker (a voice's quietest sounds). The
speech has ended once ``hangover`` seconds of frames that are not speech follow at least 0.1 s of
speech frames; the cut keeps ``pad`` seconds after the last one (a word's quiet tail). Measured on
festival's slt saying the robot's 32 commands under pink noise at 10 dB SNR, these settings with a
0.2 s pad cut one of them 0.03 s before the end of its last word (at -40 dBFS) and no other before
it (python -m bench.figures.end_of_speech --detector); the unaveraged frames with the lowest as the floor
cut two (0.05 and 0.12 s early), a 3 or 4 dB margin or a 60 ms average cut four to six.

Every decision is a function of the samples alone, in float64: the same audio gives the same end
whatever blocks it came in, on every CPU, at any load.
"""

import math
from typing import List, Optional

import numpy as np

FRAME_SECONDS = 0.02
AVERAGED_FRAMES = 5  # 100 ms
FLOOR_PERCENTILE = 10.0
# Averaged frame energies (mean squares): speech is above both bounds.
ABOVE_FLOOR = 4.0  # 6 dB over the utterance's floor
BELOW_LEVEL = 1e-3  # 30 dB under the loudest frame heard
# 0.1 s of sound, which the average spreads over 4 frames more: a click in the room before the
# speech is no speech that ended.
LEAST_SPEECH_FRAMES = 5 + AVERAGED_FRAMES - 1
PAD_SECONDS = 0.2


class SpeechEnds:
    """The frames of the utterance being collected, and where its speech ended."""

    def __init__(self, sample_rate: int, hangover: float) -> None:
        self._frame = max(1, int(FRAME_SECONDS * sample_rate))
        self._hangover_frames = max(1, math.ceil(hangover / FRAME_SECONDS - 1e-9))
        self._pad = round(min(PAD_SECONDS, hangover) * sample_rate)
        self._energies: List[float] = []
        self._rest = np.zeros(0, dtype=np.float64)
        # _speech() of the frames so far, until more come: the turn rules ask up to four times a block
        self._speech_frames: Optional[np.ndarray] = None
        self.samples = 0  # taken so far
        # The loudest frame of this speaker: kept across a cut at the end of speech, so that the
        # room sound after it is not measured against itself.
        self.level = 0.0

    def add(self, samples: np.ndarray) -> None:
        """The next samples of the utterance."""
        audio = np.concatenate([self._rest, np.asarray(samples, dtype=np.float64)])
        whole = audio.size // self._frame * self._frame
        if whole:
            energies = np.mean(np.square(audio[:whole]).reshape(-1, self._frame), axis=1)
            self._energies.extend(energies.tolist())
            self.level = max(self.level, float(energies.max()))
            self._speech_frames = None
        self._rest = audio[whole:]
        self.samples += int(np.asarray(samples).size)

    def restart(self, audio: np.ndarray, keep_level: bool) -> None:
        """A new utterance begins with ``audio``; ``keep_level``: the same speaker goes on."""
        level = self.level if keep_level else 0.0
        self._energies, self._rest, self.samples, self.level = [], self._rest[:0], 0, level
        self._speech_frames = None
        self.add(audio)

    def _speech(self) -> np.ndarray:
        if self._speech_frames is None:
            self._speech_frames = self._speech_now()
        return self._speech_frames

    def _speech_now(self) -> np.ndarray:
        """Whether each frame so far is speech."""
        energies = np.array(self._energies)
        window = np.ones(AVERAGED_FRAMES)
        averaged = np.convolve(energies, window, "same") / np.convolve(np.ones(energies.size), window, "same")
        floor = float(np.percentile(averaged, FLOOR_PERCENTILE))
        return np.asarray(averaged > max(floor * ABOVE_FLOOR, self.level * BELOW_LEVEL))

    def heard_speech(self) -> bool:
        """Whether 0.1 s of frames so far are speech."""
        return bool(self._energies) and int(self._speech().sum()) >= LEAST_SPEECH_FRAMES

    def _last_speech_frame(self) -> Optional[int]:
        if not self._energies:
            return None
        speech = np.flatnonzero(self._speech())
        return int(speech[-1]) if speech.size >= LEAST_SPEECH_FRAMES else None

    def end(self) -> Optional[int]:
        """Where to cut the speech heard so far, however little follows it (None: no speech):
        ``pad`` after its last frame, within the samples taken."""
        last = self._last_speech_frame()
        return None if last is None else min((last + 1) * self._frame + self._pad, self.samples)

    def padded_end(self) -> Optional[int]:
        """end(), once its ``pad`` has been taken: the audio up to it is there to transcribe."""
        last = self._last_speech_frame()
        if last is None or (last + 1) * self._frame + self._pad > self.samples:
            return None
        return self.end()

    def heard_end(self) -> Optional[int]:
        """end(), once ``hangover`` of non-speech follows the speech (None: not yet)."""
        last = self._last_speech_frame()
        if last is None or len(self._energies) - 1 - last < self._hangover_frames:
            return None
        return self.end()
