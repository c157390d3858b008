"""Who speaks in the recordings of people (python -m bench.figures.speaker_pitch), issue 43's "men and
women, and say which": no set here labels its speakers, so each speaker's voice pitch is estimated,
the median fundamental frequency of their voiced 40 ms frames (the autocorrelation's peak between 60
and 400 Hz, frames within 10 dB of the loudest and clearly periodic). Adult men speak at about 85 to
155 Hz, women at about 165 to 255 Hz; a speaker between is left undecided, and a few frames make a
rough figure. Printed per set: each speaker's median, and how many are likely men and women.
"""

import collections
from pathlib import Path
from typing import Dict, List

import numpy as np

from fixtures import recordings
from fixtures.noises import read_audio
from fixtures.recordings import FSDD, SPEECH_COMMANDS

RATE = 16000
FRAME = int(0.04 * RATE)
LOWEST, HIGHEST = 60, 400  # Hz
PERIODIC = 0.4  # the autocorrelation's peak against its value at lag 0
MEN_BELOW, WOMEN_ABOVE = 155.0, 165.0


def pitches(path: Path) -> List[float]:
    """The fundamental frequency of each voiced frame of the recording at ``path``."""
    audio = read_audio(path, RATE).astype(np.float64)
    frames = [audio[start : start + FRAME] for start in range(0, audio.size - FRAME, FRAME // 2)]
    loudest = max(float(np.mean(frame * frame)) for frame in frames)
    found = []
    for frame in frames:
        if np.mean(frame * frame) < 0.1 * loudest:
            continue
        centred = frame - frame.mean()
        correlation = np.correlate(centred, centred, "full")[FRAME - 1 :]
        shortest, longest = RATE // HIGHEST, RATE // LOWEST
        lag = shortest + int(np.argmax(correlation[shortest:longest]))
        if correlation[lag] > PERIODIC * correlation[0]:
            found.append(RATE / lag)
    return found


def voice(median: float) -> str:
    """A speaker's likely voice from the median pitch of their voiced frames."""
    return "man" if median < MEN_BELOW else "woman" if median > WOMEN_ABOVE else "undecided"


def speech_commands_pitches() -> Dict[str, List[float]]:
    """The pitches of each Speech Commands speaker's voiced frames, in all their clips here."""
    speakers: Dict[str, List[float]] = collections.defaultdict(list)
    for path in sorted(SPEECH_COMMANDS.glob("*/*.wav")):
        speakers[path.stem.split("_")[0]] += pitches(path)
    return speakers


def speech_commands_voices() -> Dict[str, str]:
    """Each Speech Commands speaker's likely voice."""
    return {
        speaker: voice(float(np.median(values))) if values else "undecided"
        for speaker, values in speech_commands_pitches().items()
    }


def report(name: str, speakers: Dict[str, List[float]]) -> None:
    medians = {speaker: float(np.median(values)) for speaker, values in speakers.items() if values}
    voices = [voice(median) for median in medians.values()]
    men, women, undecided = (voices.count(kind) for kind in ("man", "woman", "undecided"))
    print(f"{name}: {len(medians)} speakers, likely {men} men and {women} women, {undecided} undecided")
    print("  " + ", ".join(f"{speaker} {median:.0f} Hz" for speaker, median in sorted(medians.items())))


def main() -> None:
    fsdd: Dict[str, List[float]] = collections.defaultdict(list)
    for path in sorted(FSDD.glob("*.wav")):
        fsdd[path.stem.split("_")[1]] += pitches(path)
    report("FSDD (tests/recordings/fsdd)", fsdd)
    report("Speech Commands (tests/recordings/speech_commands)", speech_commands_pitches())
    debian = {
        "cards": [value for recording in recordings.cards() for value in pitches(recording.path)],
        "librivox": [value for recording in recordings.librivox() for value in pitches(recording.path)],
    }
    report("pocketsphinx-testdata (one reader a set)", debian)


if __name__ == "__main__":
    main()
