"""The Whisper family: its features, Whisper's decoding rules, the model directory's checks, long
audio, languages, and the tones Whisper model (fixtures/whisper_tones_model.py) through the engine."""

import dataclasses
import json
import shutil
from pathlib import Path
from typing import Dict, List, Sequence

import numpy as np
import pytest

from fixtures.application import run_application
from fixtures.audio import noise, speak_tones
from fixtures.cancelling import failures_of_a_cancelled_transcription
from fixtures.recorded_decoding import RecordedDecoding
from fixtures.whisper_tones_model import MANIFEST as TONES_MANIFEST
from fixtures.whisper_tones_model import whisper_tones_model_directory
from speech_event.errors import ModelError
from speech_event.exporters.whisper import parse_language
from speech_event.exporters.whisper_directory import languages_of
from speech_event.grammar import phrases_grammar, requested_grammar
from speech_event.pipeline.resample import resample
from speech_event.recognizers.onnx.mel import mel_filterbank
from speech_event.recognizers.whisper.features import whisper_log_mel
from speech_event.recognizers.whisper.greedy import whisper_greedy
from speech_event.recognizers.whisper.manifest import load_tokens, text_of, token_lines
from speech_event.recognizers.whisper.model import WhisperModel
from speech_event.recognizers.whisper.recognizer import (
    WhisperRecognizer,
    compression_ratio,
    pieces_at_quiet_points,
)

RATE = 16000
# A small vocabulary: 0-4 text, 5 eot, 6 sot, 7 en, 8 transcribe, 9 no_speech, 10 no timestamps,
# 11 the first timestamp.
MANIFEST = dataclasses.replace(
    TONES_MANIFEST,
    vocabulary_size=12,
    text_context=16,
    sot=6,
    eot=5,
    no_timestamps=10,
    timestamp_begin=11,
    languages={"english": 7},
    suppress=(6, 8, 9),
    suppress_at_start=(0, 5),  # " " (token 0 here) and eot
    transcribe=8,
    no_speech=9,
)


def _scripted(best: Sequence[int], calls: List[List[int]]) -> object:
    """A decoder whose best token for the n-th position after the prompt is best[n]; a step's
    logits put 2 on the best, 1 on eot and on token 0, 0 elsewhere."""
    position = [0]

    def step(tokens: Sequence[int]) -> np.ndarray:
        calls.append(list(tokens))
        rows = []
        for _ in tokens:
            row = np.zeros(MANIFEST.vocabulary_size, np.float32)
            row[[MANIFEST.eot, 0]] = 1.0
            index = position[0] - 3  # the 4th prompt position predicts the first sampled token
            if 0 <= index < len(best):
                row[best[index]] = 2.0
            if position[0] == 0:
                row[MANIFEST.no_speech] = 3.0
            rows.append(row)
            position[0] += 1
        return np.array(rows)

    return step


def test_greedy_decoding_follows_whispers_rules() -> None:
    calls: List[List[int]] = []
    # position 1: no_speech is suppressed however high; the first step may be neither " " (0) nor eot
    result = whisper_greedy(_scripted([9, 3, 4, 5], calls), MANIFEST.prompt("english"), MANIFEST)  # type: ignore[arg-type]
    assert result.tokens == [1, 3, 4]  # 9 suppressed: eot and 0 (1) ruled out at the start, then 1
    assert calls == [[6, 7, 8, 10], [1], [3], [4]]  # the prompt once, then a token a step (the cache)
    at_sot = np.zeros(MANIFEST.vocabulary_size)
    at_sot[[MANIFEST.eot, 0]], at_sot[MANIFEST.no_speech] = 1.0, 3.0
    assert result.no_speech_prob == pytest.approx(np.exp(3) / np.exp(at_sot).sum())


def test_greedy_decoding_stops_after_sample_len_tokens() -> None:
    calls: List[List[int]] = []
    result = whisper_greedy(_scripted([2] * 20, calls), MANIFEST.prompt("english"), MANIFEST)  # type: ignore[arg-type]
    assert result.tokens == [2] * MANIFEST.sample_len  # half the text context
    assert len(calls) == MANIFEST.sample_len  # no step after the last token


def test_an_english_only_prompt_has_neither_language_nor_task() -> None:
    english_only = dataclasses.replace(MANIFEST, languages={"english": None}, transcribe=None)
    assert english_only.prompt("english") == [MANIFEST.sot, MANIFEST.no_timestamps]


def test_text_leaves_out_timestamps_and_replaces_broken_utf8() -> None:
    pieces = [b" he", b"llo", b"\xc3", b"\xa9", b"\xff", b"<|0.00|>"]
    assert text_of([0, 1, 5, 2, 3], pieces, timestamp_begin=5) == " hello\u00e9"
    assert text_of([4], pieces, timestamp_begin=5) == "\ufffd"


def test_tokens_round_trip_and_a_broken_file_is_named(tmp_path: Path) -> None:
    path = tmp_path / "tokens.txt"
    path.write_text(token_lines([b" a", b"\x00\xff", b"<|endoftext|>"]))
    assert load_tokens(path) == [b" a", b"\x00\xff", b"<|endoftext|>"]
    path.write_text("not base64!\n")
    with pytest.raises(ModelError) as error:
        load_tokens(path)
    assert str(error.value) == f"{path}: not a tokens file (one token's bytes in base64 a line)"


def _whisper_log_mel(audio: np.ndarray, mel_bands: int) -> np.ndarray:
    """whisper.log_mel_spectrogram(audio, padding=N_SAMPLES)[:, :3000] step by step as whisper writes
    it, in numpy: 30 s of silence after the audio, torch.stft's frames (centred, reflected, periodic
    Hann), the last dropped, the mel filters, log10 clamped, floored 8 under the maximum."""
    padded = np.concatenate([audio.astype(np.float64), np.zeros(30 * RATE)])
    signal = np.pad(padded, 200, mode="reflect")
    frames = 1 + (signal.size - 400) // 160
    window = np.hanning(401)[:-1]  # periodic
    stft = np.stack([np.fft.rfft(signal[i * 160 : i * 160 + 400] * window) for i in range(frames)], axis=1)
    power = np.abs(stft[:, :-1]) ** 2
    log_spec = np.log10(np.clip(mel_filterbank(RATE, 400, mel_bands).astype(np.float32) @ power, 1e-10, None))
    return np.asarray(((np.maximum(log_spec, log_spec.max() - 8.0) + 4.0) / 4.0)[:, :3000])


def test_the_features_are_whispers_log_mel_of_the_audio_and_30_s_of_silence() -> None:
    # 1 s of a 1 kHz tone and 77 samples more. After the audio's frames the window is the
    # silence's floor, 8 decades under the maximum (whisper.transcribe v20230307 to v20231117), not
    # the zeros its pad_or_trim of the mel gives since v20240927, as faster-whisper's does
    # (docs/engines.md: beside faster-whisper)
    samples = RATE + 77
    tone = (0.5 * np.sin(2 * np.pi * 1000 * np.arange(samples) / RATE)).astype(np.float32)
    mel = whisper_log_mel(tone, 80)
    assert mel.shape == (80, 3000)
    np.testing.assert_allclose(mel, _whisper_log_mel(tone, 80), rtol=0, atol=1e-6)
    assert mel.max() - mel.min() == pytest.approx(2.0)  # floored 8 decades (/4) under the maximum
    peak_band = int(np.argmax(mel[:, 50]))
    assert peak_band == int(np.argmax(mel_filterbank(RATE, 400, 80)[:, 1000 * 400 // RATE]))
    assert np.all(mel[:, 150:] == mel.min())  # after the second of tone: the padding's silence
    silence = whisper_log_mel(np.zeros(RATE // 2, np.float32), 80)  # log10(1e-10), (-10 + 4) / 4
    assert np.all(silence == -1.5)


def test_long_audio_is_cut_at_its_quietest_point_after_20_s() -> None:
    audio = noise(70 * RATE, -20.0, np.random.default_rng(0))
    audio[int(26.3 * RATE) : int(26.6 * RATE)] = 0.0  # quiet: cut here
    audio[int(49.0 * RATE) : int(49.2 * RATE)] = 0.0  # the second piece's quiet point, 22.8 s into it
    pieces = pieces_at_quiet_points(audio)
    assert [piece.size for piece in pieces] == [int(26.35 * RATE), int(22.75 * RATE), int(20.9 * RATE)]
    assert np.array_equal(np.concatenate(pieces), audio)  # nothing lost, nothing repeated


@pytest.fixture(scope="module")
def engine() -> WhisperRecognizer:
    return WhisperRecognizer(whisper_tones_model_directory(), "english")


def _speech(text: str) -> np.ndarray:
    return resample(speak_tones(text, 48000), 48000, RATE)


def test_cancel_stops_a_running_transcription_and_the_next_one_runs(engine: WhisperRecognizer) -> None:
    failures = failures_of_a_cancelled_transcription(
        engine, noise(120 * RATE, -20.0, np.random.default_rng(5))
    )
    assert len(failures) == 1
    assert "terminate" in str(failures[0]).lower()
    assert engine.transcribe(_speech("stop")).text == "stop"  # the cancel was for that run only


def test_the_tones_model_transcribes_and_reports_1_minus_no_speech_prob(engine: WhisperRecognizer) -> None:
    transcript = engine.transcribe(_speech("go to the kitchen"))
    assert transcript.text == "go to the kitchen"
    # at sot nothing is looked up: the end of text scores 5.1, the first timestamp 4, the 61 others 0
    no_speech = 1 / (61 + np.exp(5.1) + np.exp(4.0))
    assert transcript.confidence == pytest.approx(1 - no_speech)


def test_noise_alone_is_no_text_and_low_confidence(engine: WhisperRecognizer) -> None:
    transcript = engine.transcribe(noise(RATE, -40.0, np.random.default_rng(1)))
    assert transcript.text == ""
    assert transcript.confidence is not None and transcript.confidence < 0.5


def test_within_a_grammar_the_prompt_runs_once_for_the_free_text_and_every_phrase(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    grammar = requested_grammar("stop|go left")
    engine = WhisperRecognizer(whisper_tones_model_directory(), "english", grammar=grammar)
    passes: List[List[int]] = []
    decoding = WhisperModel.decoding
    monkeypatch.setattr(
        WhisperModel,
        "decoding",
        lambda model, mel, run=None: RecordedDecoding(decoding(model, mel, run), passes),
    )
    assert engine.transcribe(_speech("stop")).text == "stop"
    # the prompt first, then the free text token by token and each phrase's forms, all from its
    # cache; then the prompt over silence, once, for the audio's evidence for the free text's phrase
    prompt = TONES_MANIFEST.prompt("english")
    assert passes[0] == prompt
    with_prompt = [index for index, tokens in enumerate(passes) if TONES_MANIFEST.sot in tokens]
    assert [passes[index] for index in with_prompt] == [prompt, prompt]
    assert with_prompt[1] > 3
    engine.transcribe(_speech("stop"))
    assert sum(TONES_MANIFEST.sot in tokens for tokens in passes) == 3  # silence's pass is kept


def test_speech_longer_than_30_s_is_transcribed_piece_by_piece() -> None:
    words = ["alpha", "bravo", "charlie", "delta"]
    speech = _speech(" ".join(words * 8))  # about 10.6 s
    pause = np.zeros(RATE, np.float32)
    audio = np.concatenate([speech, pause, speech, pause, speech])
    assert audio.size > 30 * RATE  # cut in the second pause, 22 s in
    # eight times the same four words compress as a decoding loop does: whisper's test is off here
    engine = WhisperRecognizer(whisper_tones_model_directory(), "english", compression_ratio_threshold=None)
    assert engine.transcribe(audio).text == " ".join(words * 24)


def test_a_piece_that_compresses_as_a_decoding_loop_gives_no_text(engine: WhisperRecognizer) -> None:
    looping = _speech(" ".join(["alpha", "bravo", "charlie", "delta"] * 8))
    assert compression_ratio(" ".join(["alpha", "bravo", "charlie", "delta"] * 8)) > 2.4
    assert engine.transcribe(looping).text == ""
    assert engine.transcribe(_speech("alpha bravo charlie delta")).text == "alpha bravo charlie delta"


def test_kinyarwanda_uses_the_token_the_fine_tuned_model_names() -> None:
    recognizer = WhisperRecognizer(whisper_tones_model_directory(), "kinyarwanda")
    assert recognizer.transcribe(_speech("muraho")).text == "muraho"


def test_a_language_without_a_token_is_refused_when_the_engine_is_built(tmp_path: Path) -> None:
    directory = shutil.copytree(whisper_tones_model_directory(), tmp_path / "model")
    config = json.loads((directory / "config.json").read_text())
    config["languages"] = {"english": config["languages"]["english"]}
    (directory / "config.json").write_text(json.dumps(config))
    with pytest.raises(ModelError) as error:
        WhisperRecognizer(directory, "kinyarwanda")
    assert str(error.value) == (
        f"the Whisper model in {directory} has no language token for kinyarwanda (Whisper has none for "
        "Kinyarwanda; this model's languages: english); export a checkpoint fine-tuned with one, naming it: "
        "speech-event export-whisper CHECKPOINT DIR --language kinyarwanda=CODE"
    )


def test_a_missing_decoder_and_mismatched_tokens_are_named(tmp_path: Path) -> None:
    directory = shutil.copytree(whisper_tones_model_directory(), tmp_path / "model")
    (directory / "tokens.txt").write_text(token_lines([b"a"] * 10))
    with pytest.raises(ModelError) as error:
        WhisperRecognizer(directory, "english")
    assert str(error.value) == (
        f"{directory}: the tokenizer's files hold 10 tokens, config.json says {TONES_MANIFEST.vocabulary_size}, "
        f"the decoder gives {TONES_MANIFEST.vocabulary_size} logits: the files are not of one export"
    )
    (directory / "decoder.onnx").unlink()
    with pytest.raises(ModelError) as error:
        WhisperRecognizer(directory, "english")
    assert str(error.value) == (
        f"{directory}: missing decoder.onnx; a Whisper model directory holds encoder.onnx, decoder.onnx, "
        "tokens.txt and config.json (speech-event export-whisper CHECKPOINT DIR writes one)"
    )


def test_a_checkpoint_given_directly_says_how_to_export_it(tmp_path: Path) -> None:
    with pytest.raises(ModelError) as error:
        WhisperRecognizer(tmp_path / "base.pt", "english")
    assert str(error.value) == (
        f"{tmp_path / 'base.pt'} is a .pt file, not an exported model directory: export it once with "
        f"'speech-event export-whisper {tmp_path / 'base.pt'} OUT_DIR' (needs the 'export' extra), then give OUT_DIR"
    )


def test_the_exporter_maps_languages_to_whisper_tokens() -> None:
    tokens = {"en": 50259, "sw": 50318}
    assert languages_of(True, {"kinyarwanda": "sw"}, tokens.__getitem__) == {
        "english": 50259,
        "kinyarwanda": 50318,
    }
    assert languages_of(False, {}, tokens.__getitem__) == {"english": None}
    with pytest.raises(ModelError):
        languages_of(False, {"kinyarwanda": "sw"}, tokens.__getitem__)
    assert parse_language("kinyarwanda=sw") == ("kinyarwanda", "sw")


def test_without_openai_whisper_the_export_of_a_checkpoint_says_how_to_get_it(tmp_path: Path) -> None:
    result = run_application("export-whisper", "base", str(tmp_path))
    assert result.returncode == 2
    assert result.stderr == (
        "error: base is not a faster-whisper directory (a directory with model.bin), so export-whisper reads it "
        "as an openai-whisper checkpoint, which needs openai-whisper: pip install 'speech-event[export]' "
        "(openai-whisper and torch); only for exporting, never on the robot\n"
    )


@pytest.fixture
def encoded(monkeypatch: pytest.MonkeyPatch) -> List[str]:
    """What the Whisper models encode from now on: "silence" or "audio", in order."""
    seen: List[str] = []
    encode = WhisperModel.encode

    def counted(model: WhisperModel, mel: np.ndarray, run: object = None) -> Dict[str, np.ndarray]:
        seen.append("silence" if np.ptp(mel) == 0 else "audio")  # zeros: one value everywhere
        return encode(model, mel)

    monkeypatch.setattr(WhisperModel, "encode", counted)
    return seen


def test_silence_is_encoded_once_in_the_engines_life_and_never_for_free_speech(encoded: List[str]) -> None:
    engine = WhisperRecognizer(whisper_tones_model_directory(), "english")
    assert engine.transcribe(_speech("go left")).text == "go left"
    assert encoded == ["audio"]
    engine.use_grammar(requested_grammar("stop|go left"))
    assert engine.transcribe(_speech("stop")).text == "stop"  # the free text is a phrase: its evidence
    assert engine.transcribe(_speech("go lefts")).text == ""  # a near miss, 9 nats below: no candidate
    assert engine.transcribe(_speech("go left")).text == "go left"
    assert encoded == ["audio", "audio", "silence", "audio", "audio"]


def test_a_grammar_checked_has_the_silence_encoded_before_its_first_command_is_said(
    encoded: List[str],
) -> None:
    engine = WhisperRecognizer(whisper_tones_model_directory(), "english")
    grammar = phrases_grammar(["stop", "go left"], "stop|go left")
    engine.check_grammar(grammar)  # as set_grammar and the grammar key do, before it is used
    assert encoded == ["silence"]
    engine.use_grammar(grammar)
    assert engine.transcribe(_speech("stop")).text == "stop"  # its evidence: the silence of before
    engine.check_grammar(phrases_grammar(["stop"], "stop"))
    assert encoded == ["silence", "audio"]
