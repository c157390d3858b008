"""The Whisper family on onnxruntime: Whisper's log-mel -> encoder -> greedy decoding with
Whisper's rules (decoder with a key/value cache) -> tokens -> text.

Audio longer than 30 s (Whisper's window) is cut at its quietest 0.1 s between 20 and 30 s into
each piece; the pieces' texts are joined. Confidence: 1 - no_speech_prob of the first piece, as
the robot's node reports it. A language with no token in the model directory's config.json (Whisper
has none for Kinyarwanda) is refused when the engine is built.
"""

from pathlib import Path
from typing import List, Optional, Union

import numpy as np
import onnxruntime

from speech_event.errors import ModelError
from speech_event.ports import Transcript
from speech_event.recognizers.onnx.directory import exported_directory
from speech_event.recognizers.onnx.session import StoppableRuns
from speech_event.recognizers.whisper.features import CHUNK_SAMPLES, SAMPLE_RATE, whisper_log_mel
from speech_event.recognizers.whisper.greedy import WhisperResult, whisper_greedy
from speech_event.recognizers.whisper.manifest import (
    MANIFEST_FILE,
    TOKENS_FILE,
    load_tokens,
    load_whisper_manifest,
    text_of,
)
from speech_event.recognizers.whisper.model import DecoderSession, WhisperModel

SHORTEST_PIECE = 20 * SAMPLE_RATE
QUIET_WINDOW = SAMPLE_RATE // 10


def pieces_at_quiet_points(audio: np.ndarray) -> List[np.ndarray]:
    """``audio`` in pieces of at most 30 s, each cut at the quietest 0.1 s window from 20 s on."""
    pieces: List[np.ndarray] = []
    while audio.size > CHUNK_SAMPLES:
        search = audio[SHORTEST_PIECE:CHUNK_SAMPLES]
        windows = search[: search.size // QUIET_WINDOW * QUIET_WINDOW].reshape(-1, QUIET_WINDOW)
        quietest = int(np.argmin(np.square(windows.astype(np.float64)).sum(axis=1)))
        cut = SHORTEST_PIECE + quietest * QUIET_WINDOW + QUIET_WINDOW // 2
        pieces.append(audio[:cut])
        audio = audio[cut:]
    pieces.append(audio)
    return pieces


class WhisperRecognizer:
    """The Recognizer port on an exported Whisper model directory, for one language; Stoppable."""

    def __init__(self, model_directory: Union[str, Path], language: str, cuda: bool = False) -> None:
        directory = exported_directory(model_directory, ".pt", "export-whisper")
        self._manifest = load_whisper_manifest(directory / MANIFEST_FILE)
        if language not in self._manifest.languages:
            named = ", ".join(sorted(self._manifest.languages)) or "none"
            raise ModelError(
                f"the Whisper model in {directory} has no language token for {language} (Whisper has "
                f"none for Kinyarwanda; this model's languages: {named}); export a checkpoint fine-tuned "
                f"with one, naming it: speech-event export-whisper CHECKPOINT DIR --language {language}=CODE"
            )
        self._prompt = self._manifest.prompt(language)
        self._pieces = load_tokens(directory / TOKENS_FILE)
        self._model = WhisperModel(directory, cuda)
        if len(self._pieces) != self._manifest.vocabulary_size or self._model.vocabulary_size not in (
            None,
            self._manifest.vocabulary_size,
        ):
            raise ModelError(
                f"{directory}: {TOKENS_FILE} has {len(self._pieces)} tokens, {MANIFEST_FILE} says n_vocab "
                f"{self._manifest.vocabulary_size}, the decoder gives {self._model.vocabulary_size} logits: "
                "the files are not of one export"
            )
        self._runs = StoppableRuns()

    @property
    def sample_rate(self) -> int:
        return SAMPLE_RATE

    def decode(self, audio: np.ndarray, run: Optional[onnxruntime.RunOptions] = None) -> WhisperResult:
        """Whisper's greedy decoding of one piece of at most 30 s."""
        cross = self._model.encode(whisper_log_mel(audio, self._manifest.mel_bands), run)
        return whisper_greedy(DecoderSession(self._model, cross, run), self._prompt, self._manifest)

    def transcribe(self, audio: np.ndarray) -> Transcript:
        run = self._runs.start()
        results = [self.decode(piece, run) for piece in pieces_at_quiet_points(np.asarray(audio, np.float32))]
        texts = [
            text_of(result.tokens, self._pieces, self._manifest.timestamp_begin).strip() for result in results
        ]
        no_speech = results[0].no_speech_prob
        return Transcript(
            " ".join(text for text in texts if text), None if no_speech is None else 1.0 - no_speech
        )

    def stop(self) -> None:
        """Stop the transcribe running now: its next onnxruntime call raises."""
        self._runs.stop()
