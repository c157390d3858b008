"""Speech engine figures (python -m bench.figures.asr). Targets, from the issue: grammar-mode WER 0 on the
command set; real-time factors measured on 2 cores and written down.

(a) pocketsphinx on 32 tts-voice robot commands, language-model mode and grammar mode;
(b) pocketsphinx on the real recorded speech of Debian's pocketsphinx-testdata (LibriVox);
(c) the NeMo features, and the NeMo engine on models built at test time (a random one and the
tones fixture model);
(d) each model family at realistic size (random weights: the conformer-transducer large,
Parakeet-TDT 0.6B-shaped, Whisper base and small), each in a process of its own: load time,
real-time factor on 5 and 10 s of speech, peak resident memory, and what ``cuda true`` does on a
machine without CUDA. The models come from ``bench/tools/family_models.py`` (needs NeMo and
openai-whisper, once): SPEECH_EVENT_FAMILY_MODELS=DIR names where it wrote them;
(e) fp32 against int8 on those models, on 2 cores and on 1, beside onnx-asr (bench/figures/int8.py).
"""

import logging
import os
import subprocess
import sys
import tempfile
import time
import wave
from pathlib import Path
from typing import List, Sequence, Tuple

import numpy as np

from bench.figures import int8
from bench.figures.measures import peak_mib, robot_commands, word_errors
from fixtures.audio import noise, speak_tones
from fixtures.tones_model import build_tones_model
from fixtures.transducer_model import build_random_transducer
from fixtures.tts import speak_tts
from speech_event.config import SpeechEventConfig
from speech_event.grammar import phrases_grammar
from speech_event.pipeline.resample import resample
from speech_event.ports import Recognizer
from speech_event.recognizers import RECOGNIZERS
from speech_event.recognizers.nemo.features import FeatureSettings, features
from speech_event.recognizers.nemo.manifest import CONFORMER_TRANSDUCER
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.onnx.families import family_of
from speech_event.recognizers.sphinx import SphinxRecognizer
from speech_event.recognizers.whisper.features import whisper_log_mel
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

LIBRIVOX = Path("/usr/share/pocketsphinx/test/data/librivox")


def score(recognizer: Recognizer, samples: Sequence[Tuple[str, np.ndarray]]) -> Tuple[float, float]:
    """(WER, real-time factor) over (reference, 16 kHz audio) pairs."""
    edits = words = 0
    busy = audio_seconds = 0.0
    for reference, audio in samples:
        start = time.perf_counter()
        hypothesis = recognizer.transcribe(audio).text
        busy += time.perf_counter() - start
        audio_seconds += audio.size / 16000
        errors, count = word_errors(reference, hypothesis)
        edits, words = edits + errors, words + count
    return edits / words, busy / audio_seconds


def commands() -> None:
    commands = robot_commands()
    samples = [(command, speak_tts(command, 16000)) for command in commands]
    grammar = phrases_grammar(commands, "the commands")
    for mode, recognizer in (
        ("language model", SphinxRecognizer()),
        ("grammar", SphinxRecognizer(grammar=grammar)),
    ):
        wer, rtf = score(recognizer, samples)
        print(f"pocketsphinx, {len(commands)} tts commands, {mode}: WER {wer:.3f}, RTF {rtf:.3f}")


def recorded_speech() -> None:
    if not LIBRIVOX.is_dir():
        print("pocketsphinx on recorded speech: skipped, apt-get install pocketsphinx-testdata")
        return
    samples: List[Tuple[str, np.ndarray]] = []
    for line in (LIBRIVOX / "transcription").read_text().splitlines():
        text, _, file_id = line.rpartition(" (")
        with wave.open(str(LIBRIVOX / f"{file_id.rstrip(')')}.wav")) as wav:
            pcm = np.frombuffer(wav.readframes(wav.getnframes()), dtype="<i2")
        samples.append((text.replace("<s>", "").replace("</s>", "").strip(), pcm.astype(np.float32) / 32768))
    wer, rtf = score(SphinxRecognizer(), samples)
    seconds = sum(audio.size for _, audio in samples) / 16000
    print(
        f"pocketsphinx, LibriVox ({len(samples)} utterances, {seconds:.0f} s), language model: "
        f"WER {wer:.3f}, RTF {rtf:.3f}"
    )


def nemo_engine() -> None:
    audio = noise(10 * 16000, -20.0, np.random.default_rng(0))
    settings = FeatureSettings()
    start = time.perf_counter()
    for _ in range(10):
        features(audio, settings)
    print(f"NeMo features: RTF {(time.perf_counter() - start) / 100:.4f} (10 s of audio, 10 runs)")
    with tempfile.TemporaryDirectory() as work:
        model = NemoRecognizer(build_random_transducer(Path(work) / "model"))
        start = time.perf_counter()
        model.transcribe(audio)
        print(
            f"NeMo engine, small test model (32-wide encoder): RTF {(time.perf_counter() - start) / 10:.4f}"
        )
        start = time.perf_counter()
        tones = build_tones_model(Path(work) / "tones")
        built = time.perf_counter() - start
        speech = resample(speak_tones("please bring the red cup from the kitchen table", 48000), 48000, 16000)
        engine = NemoRecognizer(tones)
        start = time.perf_counter()
        text = engine.transcribe(speech).text
        rtf = (time.perf_counter() - start) / (speech.size / 16000)
        print(f"NeMo engine, tones fixture model: built in {built:.3f} s, RTF {rtf:.4f}, heard {text!r}")


class _Said(logging.Handler):
    def __init__(self) -> None:
        super().__init__()
        self.messages: List[str] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.messages.append(record.getMessage())


def _family_engine(directory: Path, cuda: bool) -> Recognizer:
    """The engine the node would build for this directory, as its family's ``model``."""
    config = SpeechEventConfig(
        language="english",
        model=family_of(directory, unrecorded=CONFORMER_TRANSDUCER),
        en_model_path=str(directory),
        cuda=cuda,
    )
    return RECOGNIZERS["auto"](config)


def _whisper_costs(engine: WhisperRecognizer, audio: np.ndarray) -> str:
    """A random model decodes as many tokens as it likes (up to 224), so its RTF says little:
    the window's cost and a token's cost, and the RTF at 4 tokens per second of speech."""
    started = time.perf_counter()  # the bench looks inside the engine
    session = engine._model.decoding(whisper_log_mel(audio, engine._manifest.mel_bands))
    window = time.perf_counter() - started
    session(engine._manifest.prompt("english"))
    started = time.perf_counter()
    for _ in range(50):
        session([engine._manifest.eot - 1])
    token = (time.perf_counter() - started) / 50
    rtf = (window + (4 + 4 * 5) * token) / 5
    costs = f"30 s window {window * 1000:.0f} ms, a token {token * 1000:.1f} ms"
    return f"{costs}: RTF {rtf:.3f} at 4 tokens/s on 5 s"


def one_family_model(directory: Path) -> None:
    """Run in a process of its own, so its peak memory is the engine's."""
    said = _Said()
    logging.getLogger("speech_event").addHandler(said)
    started = time.perf_counter()
    engine = _family_engine(directory, cuda=False)
    loaded = time.perf_counter() - started
    speech = np.concatenate([speak_tts(command, 16000) for command in robot_commands()])
    figures = []
    for seconds in (5, 10):
        audio = speech[: seconds * 16000]
        engine.transcribe(audio)  # warm
        started = time.perf_counter()
        engine.transcribe(audio)
        figures.append(f"RTF {(time.perf_counter() - started) / seconds:.3f} on {seconds} s")
    if isinstance(engine, WhisperRecognizer):
        figures.append(_whisper_costs(engine, speech[: 5 * 16000]))
    peak = peak_mib()
    _family_engine(directory, cuda=True).transcribe(speech[:16000])
    print(
        f"(d) {directory.name:20s} loaded in {loaded:.1f} s; {', '.join(figures)}; peak memory {peak:.0f} MiB"
    )
    print(f"    cuda true here: {len(said.messages)} warning(s) {said.messages}, then the CPU")


def family_models() -> None:
    where = os.environ.get("SPEECH_EVENT_FAMILY_MODELS")
    if not where:
        print("(d) set SPEECH_EVENT_FAMILY_MODELS to the directory bench/tools/family_models.py wrote")
        return
    for directory in sorted(Path(where).iterdir()):
        subprocess.run([sys.executable, "-m", "bench.figures.asr", "--one", str(directory)], check=True)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--one"]:
        one_family_model(Path(sys.argv[2]))
        sys.exit(0)
    commands()
    recorded_speech()
    nemo_engine()
    family_models()
    int8.figures([])
