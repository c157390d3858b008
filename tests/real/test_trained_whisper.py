"""The Whisper engine on trained weights: faster-whisper's tiny.en converted by export-whisper
(fixtures/trained_whisper.py), on the 10 recordings of Debian's pocketsphinx-testdata, against
CTranslate2 itself (the ``ctranslate2`` package) decoding the same model.bin.

Both are given the same log-mel, the engine's own (whisper's log_mel_spectrogram, which its tests
check): the comparison is then of the converted model and its decoding, not of two feature
extractors (faster-whisper's is its own numpy version of whisper's)."""

import json
from pathlib import Path

import ctranslate2
import numpy as np

from fixtures import recordings
from fixtures.trained_whisper import tiny_en_directory
from speech_event.recognizers.whisper.features import whisper_log_mel
from speech_event.recognizers.whisper.manifest import load_whisper_manifest
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

RECORDINGS = recordings.cards() + recordings.librivox()


def test_the_engine_suppresses_what_ctranslate2s_config_suppresses(tiny_en: Path) -> None:
    # config.json's lists, from Hugging Face's generation config, already hold whisper's special
    # tokens: CTranslate2's suppress_tokens -1 and suppress_blank are then the engine's rules
    config = json.loads((tiny_en_directory() / "config.json").read_text())
    manifest = load_whisper_manifest(tiny_en / "config.json")
    assert manifest.suppress == tuple(sorted(config["suppress_ids"]))
    assert manifest.suppress_at_start == tuple(config["suppress_ids_begin"]) == (220, manifest.eot)


def test_the_engine_gives_ctranslate2s_greedy_tokens_on_every_recording(tiny_en: Path) -> None:
    manifest = load_whisper_manifest(tiny_en / "config.json")
    audio = [recording.samples() for recording in RECORDINGS]
    # CTranslate2 at float32 (the engine's precision), beam 1, no timestamps (the prompt ends in
    # <|notimestamps|>), config.json's suppressed tokens (-1) and blank at the start. It decodes in
    # its own thread while the engine decodes (on two cores, each mostly on one); one thread of its
    # own, since beside another busy process its OpenMP threads wait on each other for seconds.
    reference = ctranslate2.models.Whisper(str(tiny_en_directory()), compute_type="float32", intra_threads=1)
    pending = reference.generate(
        ctranslate2.StorageView.from_array(
            np.stack([whisper_log_mel(samples, manifest.mel_bands) for samples in audio])
        ),
        [manifest.prompt("english")] * len(audio),
        asynchronous=True,
        beam_size=1,
        suppress_blank=True,
        suppress_tokens=[-1],
    )
    engine = WhisperRecognizer(tiny_en, "english")
    tokens = [engine.decode(samples).tokens for samples in audio]
    assert tokens == [result.result().sequences_ids[0] for result in pending]
