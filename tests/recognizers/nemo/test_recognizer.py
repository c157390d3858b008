"""The NeMo transducer engine: features against kaldi-native-fbank, greedy decoding, the vocabulary,
model errors, and the whole engine against onnx-asr on models built at test time."""

import logging
from pathlib import Path
from typing import List, Tuple

import kaldi_native_fbank as knf
import numpy as np
import onnx
import onnx_asr
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from fixtures.audio import noise, speak_tones
from fixtures.cancelling import failures_of_a_cancelled_transcription
from fixtures.transducer_model import build_random_transducer
from speech_event.errors import ModelError
from speech_event.pipeline.resample import resample
from speech_event.recognizers.nemo.features import FeatureSettings, features, log_mel
from speech_event.recognizers.nemo.recognizer import NemoRecognizer
from speech_event.recognizers.nemo.rnnt import rnnt_greedy
from speech_event.recognizers.nemo.vocabulary import Vocabulary, load_vocabulary
from speech_event.recognizers.onnx.directory import Runtime
from speech_event.recognizers.onnx.session import providers


def _kaldi_native_fbank(audio: np.ndarray) -> np.ndarray:
    extractor = knf.OnlineNemoFbank(knf.NemoFbankOptions())
    extractor.accept_waveform(16000, audio.tolist())
    extractor.input_finished()
    frames, _ = extractor.get_frames(0, extractor.num_frames_ready, True)
    return np.asarray(frames)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**16), samples=st.integers(400, 48000), level_db=st.floats(-60, -6))
def test_log_mel_matches_kaldi_native_fbank_nemo_within_1e_3(
    seed: int, samples: int, level_db: float
) -> None:
    audio = noise(samples, level_db, np.random.default_rng(seed))
    reference = _kaldi_native_fbank(audio)
    ours = log_mel(audio, FeatureSettings()).T[: len(reference)]
    assert ours.shape == reference.shape
    assert float(np.max(np.abs(ours - reference))) <= 1e-3


def test_log_mel_matches_kaldi_native_fbank_on_tones_speech() -> None:
    audio = resample(speak_tones("the quick brown fox", 48000), 48000, 16000)
    reference = _kaldi_native_fbank(audio)
    assert float(np.max(np.abs(log_mel(audio, FeatureSettings()).T[: len(reference)] - reference))) <= 1e-3


def test_features_are_normalised_per_band_over_the_utterance() -> None:
    audio = noise(16000, -20.0, np.random.default_rng(0))
    normalised = features(audio, FeatureSettings())
    assert normalised.shape == (80, 100)  # one frame per 10 ms
    assert np.allclose(normalised.mean(axis=1), 0.0, atol=1e-5)
    assert np.allclose(normalised.std(axis=1, ddof=1), 1.0, atol=1e-3)


def test_greedy_decoding_emits_until_blank_caps_symbols_and_updates_state_only_on_emission() -> None:
    blank = 3
    # frame 0 proposes tokens 1, 2 then blank; frame 1 proposes token 0 forever; frame 2 is all blank
    script = {(0, blank): 1, (0, 1): 2, (0, 2): blank, (1, 2): 0, (1, 0): 0, (2, 0): blank}
    calls: List[Tuple[int, int, int]] = []

    def step(frame: np.ndarray, last: int, state: int) -> Tuple[np.ndarray, int]:
        calls.append((int(frame[0]), last, state))
        logits = np.zeros(blank + 1)
        logits[script[(int(frame[0]), last)]] = 1.0
        return logits, state + 1

    tokens = rnnt_greedy(np.array([[0.0], [1.0], [2.0]]), step, 0, blank, max_symbols=3).tokens
    assert tokens == [1, 2, 0, 0, 0]
    # the state moves on only when a token is emitted; a blank leaves it as it was
    assert calls == [(0, 3, 0), (0, 1, 1), (0, 2, 2), (1, 2, 2), (1, 0, 3), (1, 0, 4), (2, 0, 5)]


def test_the_vocabulary_turns_word_starts_into_spaces_and_drops_control_tokens(tmp_path: Path) -> None:
    path = tmp_path / "vocab.txt"
    path.write_text("<unk> 0\n\u2581mu 1\nraho 2\n\u2581n 3\n' 4\nuko 5\n<blk> 6\n")
    vocabulary = load_vocabulary(path)
    assert (vocabulary.size, vocabulary.blank) == (7, 6)
    assert vocabulary.text([1, 2, 0, 3, 4, 5]) == "muraho n'uko"
    assert Vocabulary(["\u2581a", "<blk>"]).text([]) == ""


@pytest.mark.parametrize(
    ("content", "message"),
    [
        ("a 0\nb\n", ":2: expected 'token id', found 'b'"),
        ("a 0\nb 2\n", ": token ids must be 0 to 1, each once"),
    ],
)
def test_a_broken_vocabulary_is_named(tmp_path: Path, content: str, message: str) -> None:
    path = tmp_path / "vocab.txt"
    path.write_text(content)
    with pytest.raises(ModelError) as error:
        load_vocabulary(path)
    assert str(error.value) == f"{path}{message}"


@pytest.fixture(scope="module")
def random_model(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return build_random_transducer(tmp_path_factory.mktemp("models") / "random")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_engine_gives_the_same_text_as_onnx_asr_on_the_same_model(random_model: Path, seed: int) -> None:
    ours = NemoRecognizer(random_model)
    theirs = onnx_asr.load_model("nemo-conformer-rnnt", random_model)
    rng = np.random.default_rng(seed)
    audio = np.concatenate([noise(16000, -30.0, rng), resample(speak_tones("muraho", 48000), 48000, 16000)])
    text = ours.transcribe(audio).text
    assert text != ""
    assert text == theirs.recognize(audio)


def test_audio_shorter_than_a_frame_is_transcribed_as_a_second_of_it_as_nemo_does(random_model: Path) -> None:
    engine = NemoRecognizer(random_model)
    assert engine.hypothesis(np.zeros(100, np.float32)) == engine.hypothesis(np.zeros(16000, np.float32))
    assert engine.hypothesis(np.zeros(0, np.float32)) == engine.hypothesis(np.zeros(16000, np.float32))


def test_a_missing_model_file_is_named_with_what_a_model_directory_holds(tmp_path: Path) -> None:
    model = build_random_transducer(tmp_path / "model")
    (model / "decoder_joint-model.onnx").unlink()
    with pytest.raises(ModelError) as error:
        NemoRecognizer(model)
    assert str(error.value) == (
        f"{model}: missing decoder_joint-model.onnx; a model directory holds encoder-model.onnx, "
        "decoder_joint-model.onnx (a transducer) or model.onnx (CTC), vocab.txt and config.json "
        "(speech-event export-nemo MODEL.nemo DIR writes one)"
    )


def test_wrong_tensor_names_are_named_with_the_expected_ones(tmp_path: Path) -> None:
    model = build_random_transducer(tmp_path / "model")
    encoder = onnx.load(str(model / "encoder-model.onnx"))
    encoder.graph.input[1].name = "audio_length"
    for node in encoder.graph.node:
        node.input[:] = ["audio_length" if name == "length" else name for name in node.input]
    onnx.save(encoder, str(model / "encoder-model.onnx"))
    with pytest.raises(ModelError) as error:
        NemoRecognizer(model)
    assert str(error.value) == (
        f"{model / 'encoder-model.onnx'}: inputs are ['audio_length', 'audio_signal'] (missing length); "
        "encoder-model.onnx of a NeMo export has audio_signal (3-D), length (1-D)"
    )


def test_a_nemo_archive_given_directly_says_how_to_export_it(tmp_path: Path) -> None:
    archive = tmp_path / "stt_rw_conformer_transducer_large.nemo"
    archive.write_bytes(b"")
    with pytest.raises(ModelError) as error:
        NemoRecognizer(archive)
    assert str(error.value) == (
        f"{archive} is a .nemo file, not an exported model directory: export it once with "
        f"'speech-event export-nemo {archive} OUT_DIR' (needs the 'export' extra), then give OUT_DIR"
    )


def test_cuda_without_a_cuda_onnxruntime_warns_and_runs_on_the_cpu(
    random_model: Path, caplog: pytest.LogCaptureFixture
) -> None:
    assert providers(cuda=False) == ["CPUExecutionProvider"]
    with caplog.at_level(logging.WARNING, logger="speech_event"):
        recognizer = NemoRecognizer(random_model, Runtime(cuda=True))
    assert recognizer.transcribe(noise(16000, -20.0, np.random.default_rng(0))).text != ""
    assert caplog.messages == [
        "cuda is true but this onnxruntime has no CUDAExecutionProvider: running on the CPU"
    ]


def test_cancel_stops_a_running_transcription_and_the_next_one_runs(random_model: Path) -> None:
    engine = NemoRecognizer(random_model)
    long_audio = noise(16000 * 120, -20.0, np.random.default_rng(5))
    failures = failures_of_a_cancelled_transcription(engine, long_audio)
    assert len(failures) == 1
    assert "terminate" in str(failures[0]).lower()
    speech = resample(speak_tones("muraho", 48000), 48000, 16000)
    after = engine.transcribe(speech).text  # the cancel was for that run only
    assert after != ""
    assert after == NemoRecognizer(random_model).transcribe(speech).text
