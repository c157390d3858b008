"""speech-event export-whisper on a faster-whisper (CTranslate2) directory, with numpy and onnx
alone (speech_event/exporters/faster_whisper.py), on the small random Whisper of
fixtures/ct2_whisper_model.py stored in each of CTranslate2's quantizations: the engine's greedy
decoding equals CTranslate2's own (the ``ctranslate2`` package) token for token, logit for logit;
the manifest follows whisper's rules; each file it cannot use is named with what is allowed."""

import json
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any, Callable, Dict, List

import ctranslate2
import numpy as np
import onnx
import pytest

from fixtures import recordings
from fixtures.ct2_whisper_model import (
    EOT,
    EXPORTED_FILES,
    NO_TIMESTAMPS,
    QUANTIZATIONS,
    SOT,
    SUPPRESS_IDS_BEGIN,
    TEXT_POSITIONS,
    TEXT_TOKENS,
    VOCABULARY,
    model_bin_bytes,
    whisper_variables,
    write_whisper_directory,
)
from speech_event.errors import ModelError
from speech_event.exporters import whisper as whisper_exporter
from speech_event.exporters.faster_whisper import read_faster_whisper, whisper_manifest
from speech_event.recognizers.onnx.directory import Runtime
from speech_event.recognizers.whisper.features import whisper_log_mel
from speech_event.recognizers.whisper.greedy import whisper_greedy, whisper_logits
from speech_event.recognizers.whisper.manifest import WhisperManifest, load_tokens, load_whisper_manifest
from speech_event.recognizers.whisper.model import WhisperModel
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer

ID = {text: token for token, text in enumerate(VOCABULARY)}
SPECIALS_SUPPRESSED = [
    ID[text]
    for text in (
        "<|startoftranscript|>",
        "<|translate|>",
        "<|transcribe|>",
        "<|startoflm|>",
        "<|startofprev|>",
        "<|nocaptions|>",
    )
]
MANIFEST = WhisperManifest(
    mel_bands=80,
    vocabulary_size=len(VOCABULARY),
    text_context=TEXT_POSITIONS,
    sot=SOT,
    eot=EOT,
    no_timestamps=NO_TIMESTAMPS,
    timestamp_begin=NO_TIMESTAMPS + 1,
    languages={"english": None},  # fewer tokens than a multilingual Whisper's: English only
    suppress=tuple(sorted([ID["q"], *SPECIALS_SUPPRESSED])),
    suppress_at_start=tuple(SUPPRESS_IDS_BEGIN),
    transcribe=None,
    no_speech=ID["<|nocaptions|>"],
)


def _exported(
    tmp_path: Path, quantization: str = "float32", vocabulary_file: str = "vocabulary.json"
) -> Path:
    source = write_whisper_directory(tmp_path / "faster-whisper", quantization, vocabulary_file)
    out = tmp_path / "exported"
    assert whisper_exporter.main([str(source), str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def mel() -> np.ndarray:
    """The log-mel of a recording of speech, which both runtimes are given."""
    return whisper_log_mel(recordings.cards()[0].samples(), 80)


@pytest.mark.parametrize("quantization", list(QUANTIZATIONS))
def test_the_engine_decodes_as_ctranslate2_does_in_each_quantization(
    tmp_path: Path, quantization: str, mel: np.ndarray
) -> None:
    exported = _exported(tmp_path, quantization)
    reference = ctranslate2.models.Whisper(str(tmp_path / "faster-whisper"), compute_type="float32").generate(
        ctranslate2.StorageView.from_array(mel[None]),
        [[SOT, NO_TIMESTAMPS]],
        beam_size=1,
        suppress_blank=True,
        suppress_tokens=[-1],
        max_length=TEXT_POSITIONS,
        return_no_speech_prob=True,
        return_logits_vocab=True,
    )[0]
    manifest = load_whisper_manifest(exported / "config.json")
    model = WhisperModel(exported)
    ours = whisper_greedy(model.decoding(mel), manifest.prompt("english"), manifest)
    assert ours.tokens == reference.sequences_ids[0]
    assert len(ours.tokens) == 12  # sample_len: the random model never ends its text
    assert ours.no_speech_prob == pytest.approx(reference.no_speech_prob, abs=1e-6)
    # each step's logits, what Whisper's rules leave of them (CTranslate2 gives the rest its lowest float)
    steps = _teacher_forced(model, mel, manifest.prompt("english"), ours.tokens)
    for step, (row, expected) in enumerate(zip(steps, reference.logits[0])):
        allowed = np.isfinite(whisper_logits(row, step == 0, manifest))
        np.testing.assert_allclose(row[allowed], np.asarray(expected)[allowed], atol=2e-5)
        assert np.all(np.asarray(expected)[~allowed] == np.finfo(np.float32).min)


def test_the_manifest_adds_whispers_special_tokens_to_config_jsons_suppressed_ones(tmp_path: Path) -> None:
    directory = write_whisper_directory(tmp_path / "faster-whisper")
    _edit_json(directory / "config.json", suppress_ids=[ID["q"]])  # the specials left out
    assert read_faster_whisper(directory, {}).manifest == MANIFEST


def test_a_layer_norm_epsilon_in_config_json_is_the_models_as_ctranslate2_reads_it(tmp_path: Path) -> None:
    directory = write_whisper_directory(tmp_path / "faster-whisper")
    assert read_faster_whisper(directory, {}).weights.layer_norm_epsilon == 1e-5  # whisper's, torch's default
    _edit_json(directory / "config.json", layer_norm_epsilon=1e-6)
    assert read_faster_whisper(directory, {}).weights.layer_norm_epsilon == 1e-6


def test_tokens_txt_holds_each_tokens_bytes_from_gpt2s_byte_level_characters(tmp_path: Path) -> None:
    pieces = load_tokens(_exported(tmp_path) / "tokens.txt")
    assert pieces[: len(TEXT_TOKENS)] == [b" "] + [
        bytes([letter]) for letter in b"abcdefghijklmnopqrstuvwxyz"
    ] + [b" " + bytes([letter]) for letter in b"abcdefghijklmnopqrstuvwxyz"]
    assert pieces[EOT:] == [text.encode() for text in VOCABULARY[EOT:]]


@pytest.mark.parametrize("vocabulary_file", ["vocabulary.txt", "tokenizer.json"])
def test_the_vocabulary_may_be_ctranslate2s_older_file_or_the_tokenizer(
    tmp_path: Path, vocabulary_file: str
) -> None:
    exported = _exported(tmp_path, vocabulary_file=vocabulary_file)
    reference = _exported(tmp_path / "json")
    assert (exported / "config.json").read_text() == (reference / "config.json").read_text()
    pieces, expected = load_tokens(exported / "tokens.txt"), load_tokens(reference / "tokens.txt")
    if (
        vocabulary_file == "tokenizer.json"
    ):  # it lists no timestamps: they have no text, as whisper writes none
        expected = expected[: ID["<|0.00|>"]] + [b""] * 3
    assert pieces == expected


def test_export_whisper_int8_writes_the_int8_files_the_engine_runs(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    source = write_whisper_directory(tmp_path / "faster-whisper")
    out = tmp_path / "exported"
    assert whisper_exporter.main([str(source), str(out), "--int8"]) == 0
    assert capsys.readouterr().out.splitlines() == [
        f"wrote {out} (whisper; languages english): set model whisper and the model paths",
        f"wrote {out / 'decoder.int8.onnx'} (int8: set quantization int8 to use it)",
        f"wrote {out / 'encoder.int8.onnx'} (int8: set quantization int8 to use it)",
    ]
    audio = recordings.cards()[0].samples()
    mel = whisper_log_mel(audio, 80)
    manifest = load_whisper_manifest(out / "config.json")
    prompt = manifest.prompt("english")
    fp32, int8 = WhisperModel(out), WhisperModel(out, Runtime(int8=True))
    text = whisper_greedy(fp32.decoding(mel), prompt, manifest).tokens
    # Which token wins a near-tie of a random model's int8 logits is the CPU's kernels' to decide
    # (an AVX2 CPU and an AVX-512 one chose differently), so the tokens are not compared with fp32's:
    # along fp32's text, int8's logits are off by int8's error, far less than their spread, on every
    # x86-64 CPU (3.3 % of the largest here and under qemu as a Haswell; the 8-bit weights that AVX2
    # saturates on: 13 % there, bench/figures/int8_cpus.py), and not exactly fp32's (int8 ran)
    exact, quantized = _teacher_forced(fp32, mel, prompt, text), _teacher_forced(int8, mel, prompt, text)
    assert 0 < np.abs(quantized - exact).max() < 0.06 * np.abs(exact).max()
    # the engine, told int8, decodes those graphs greedily: its tokens are the reference's, on this CPU
    engine = WhisperRecognizer(out, "english", Runtime(int8=True))
    assert engine.decode(audio).tokens == whisper_greedy(int8.decoding(mel), prompt, manifest).tokens


def _teacher_forced(model: WhisperModel, mel: np.ndarray, prompt: List[int], text: List[int]) -> np.ndarray:
    """The logits at each position of ``text``, given the tokens before it."""
    decoding = model.decoding(mel)
    return np.stack([decoding(prompt)[-1], *(decoding([token])[-1] for token in text[:-1])])


def test_every_graph_keeps_its_weights_in_a_file_beside_it_the_int8_ones_too(tmp_path: Path) -> None:
    # so that onnxruntime reads the weights from there instead of holding the whole file parsed as
    # one protobuf beside them while it loads (exporters/graph_files.py); and Whisper large's fp32
    # graphs (about 3 GB each) cannot be one ONNX file, a protobuf message of at most 2 GiB
    source = write_whisper_directory(tmp_path / "faster-whisper")
    out = tmp_path / "exported"
    assert whisper_exporter.main([str(source), str(out), "--int8"]) == 0
    assert sorted(path.name for path in out.iterdir()) == [
        "config.json",
        "decoder.int8.onnx",
        "decoder.int8.onnx.data",
        "decoder.onnx",
        "decoder.onnx.data",
        "encoder.int8.onnx",
        "encoder.int8.onnx.data",
        "encoder.onnx",
        "encoder.onnx.data",
        "tokens.txt",
    ]
    for name in ("encoder.onnx", "decoder.onnx", "encoder.int8.onnx", "decoder.int8.onnx"):
        graph = onnx.load(str(out / name), load_external_data=False).graph
        beside = [tensor for tensor in graph.initializer if tensor.data_location == onnx.TensorProto.EXTERNAL]
        inside = [tensor for tensor in graph.initializer if tensor.data_location != onnx.TensorProto.EXTERNAL]
        assert beside and all(len(tensor.raw_data) < 1024 for tensor in inside)  # onnx's threshold
        locations = {
            entry.value for tensor in beside for entry in tensor.external_data if entry.key == "location"
        }
        assert locations == {name + ".data"}
        # readable by whoever may read the graph (onnx writes it for its owner alone)
        assert (out / f"{name}.data").stat().st_mode & 0o777 == (out / name).stat().st_mode & 0o777


def test_a_multilingual_model_maps_the_languages_named_to_their_tokens(tmp_path: Path) -> None:
    model = read_faster_whisper(write_whisper_directory(tmp_path / "faster-whisper"), {})
    # Whisper's multilingual vocabulary: 51865 tokens or more
    tokens = VOCABULARY + ["<|sw|>"] + [""] * (51865 - len(VOCABULARY) - 1)
    weights = replace(model.weights, embedding=np.zeros((51865, 16), np.float32))
    config: Dict[str, Any] = {"suppress_ids": [], "suppress_ids_begin": []}
    manifest = whisper_manifest(weights, tokens, config, {"kinyarwanda": "sw"}, tmp_path)
    assert manifest.languages == {"english": ID["<|en|>"], "kinyarwanda": len(VOCABULARY)}
    assert manifest.transcribe == ID["<|transcribe|>"]
    assert manifest.prompt("kinyarwanda") == [SOT, len(VOCABULARY), ID["<|transcribe|>"], NO_TIMESTAMPS]
    with pytest.raises(ModelError, match=r"no language token <\|fr\|>"):
        whisper_manifest(weights, tokens, config, {"french": "fr"}, tmp_path)


def _edit_json(path: Path, **changes: Any) -> None:
    document = json.loads(path.read_text())
    for key, value in changes.items():
        if value is None:
            del document[key]
        else:
            document[key] = value
    path.write_text(json.dumps(document))


def _without_variable(name: str) -> Callable[[Path], None]:
    def change(directory: Path) -> None:
        variables, aliases = whisper_variables("float32")
        kept = [variable for variable in variables if variable[0] != name]
        (directory / "model.bin").write_bytes(model_bin_bytes(kept, aliases))

    return change


def _without_blocks(coder: str) -> Callable[[Path], None]:
    def change(directory: Path) -> None:
        variables, aliases = whisper_variables("float32")
        kept = [variable for variable in variables if not variable[0].startswith(f"{coder}/layer_")]
        (directory / "model.bin").write_bytes(model_bin_bytes(kept, aliases))

    return change


def _with_header(**header: Any) -> Callable[[Path], None]:
    def change(directory: Path) -> None:
        variables, aliases = whisper_variables("float32")
        (directory / "model.bin").write_bytes(model_bin_bytes(variables, aliases, **header))

    return change


def _vocabulary(tokens: List[str]) -> Callable[[Path], None]:
    def change(directory: Path) -> None:
        (directory / "vocabulary.json").write_text(json.dumps(tokens))

    return change


DIRECTORY = (
    "a faster-whisper (CTranslate2) model directory holds model.bin, config.json and vocabulary.json, "
    "vocabulary.txt or tokenizer.json"
)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda d: (d / "config.json").unlink(), f": missing config.json; {DIRECTORY}"),
        (lambda d: (d / "config.json").write_text("{"), "/config.json: not JSON (Expecting property name"),
        (
            lambda d: _edit_json(d / "config.json", suppress_ids_begin=None),
            "/config.json: no list of token ids 'suppress_ids_begin'; CTranslate2's Whisper config has "
            "suppress_ids and suppress_ids_begin, which Whisper's decoding rules need",
        ),
        (lambda d: (d / "vocabulary.json").unlink(), f": no vocabulary; {DIRECTORY}"),
        (
            lambda d: (d / "vocabulary.json").write_text("[1, 2]"),
            "/vocabulary.json: not a JSON list of token texts",
        ),
        (
            _vocabulary([*VOCABULARY, "<|0.06|>"]),
            "/vocabulary.json: 66 tokens, but {directory}/model.bin embeds 65: not of one model",
        ),
        (
            _vocabulary(["a b", *VOCABULARY[1:]]),
            "/vocabulary.json: token 0 'a b' has ' ', not a character of GPT-2's byte-level mapping "
            "(Whisper's tokenizer)",
        ),
        (
            _vocabulary([text.replace("notimestamps", "nots") for text in VOCABULARY]),
            "/vocabulary.json: no special token <|notimestamps|>; Whisper's tokenizer has it",
        ),
        (
            _with_header(spec="TransformerSpec"),
            "/model.bin: a CTranslate2 TransformerSpec model, not Whisper (WhisperSpec)",
        ),
        (
            _with_header(revision=4),
            "/model.bin: WhisperSpec revision 4; revisions 1 to 3 can be read (a later CTranslate2 wrote it)",
        ),
        (
            _without_variable("decoder/num_heads"),
            "/model.bin: no variable decoder/num_heads in this WhisperSpec model",
        ),
        (
            _without_blocks("encoder"),
            "/model.bin: no encoder/layer_0; a Whisper model of CTranslate2 has its blocks",
        ),
        (
            _without_variable("decoder/layer_0/ffn/linear_0/weight"),
            "/model.bin: no variable decoder/layer_0/ffn/linear_0/weight in this WhisperSpec model",
        ),
    ],
    ids=[
        "no-config",
        "config-not-json",
        "no-suppress-ids-begin",
        "no-vocabulary",
        "vocabulary-not-texts",
        "more-tokens",
        "not-byte-level",
        "no-notimestamps",
        "other-spec",
        "later-revision",
        "no-heads",
        "no-blocks",
        "no-weight",
    ],
)
def test_a_directory_it_cannot_use_names_the_file_and_what_is_allowed(
    tmp_path: Path, change: Callable[[Path], None], message: str
) -> None:
    directory = write_whisper_directory(tmp_path / "faster-whisper")
    change(directory)
    with pytest.raises(ModelError) as error:
        read_faster_whisper(directory, {})
    assert str(error.value).startswith(f"{directory}{message}".replace("{directory}", str(directory)))


def test_an_english_only_model_takes_no_other_language(tmp_path: Path) -> None:
    directory = write_whisper_directory(tmp_path / "faster-whisper")
    with pytest.raises(ModelError) as error:
        read_faster_whisper(directory, {"kinyarwanda": "sw"})
    assert str(error.value) == "an English-only checkpoint serves english only; --language cannot add another"


def test_the_export_imports_neither_torch_openai_whisper_nor_ctranslate2(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    for blocked in ("torch", "whisper", "ctranslate2", "faster_whisper"):
        monkeypatch.setitem(sys.modules, blocked, None)  # an import of it raises ImportError
    directory = write_whisper_directory(tmp_path / "faster-whisper")
    assert whisper_exporter.export(str(directory), tmp_path / "out", {}) == MANIFEST
    assert sorted(path.name for path in (tmp_path / "out").iterdir()) == EXPORTED_FILES


def test_without_onnx_the_export_says_what_to_install(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the robot's install has onnxruntime, not onnx, which only writing the graphs needs
    monkeypatch.setitem(sys.modules, "onnx", None)
    monkeypatch.setitem(sys.modules, "speech_event.exporters.whisper_graphs", None)
    directory = write_whisper_directory(tmp_path / "faster-whisper")
    with pytest.raises(ModelError) as error:
        whisper_exporter.export(str(directory), tmp_path / "out", {})
    assert str(error.value) == (
        "export-whisper writes the ONNX graphs with the onnx package: pip install onnx (a faster-whisper "
        "directory needs neither torch nor openai-whisper)"
    )
    assert not (tmp_path / "out").exists()
