"""The Whisper engine on Hugging Face optimum's layout (fixtures/whisper_tones_optimum.py: the tones
Whisper model wrapped in optimum's file names, merged decoder and transformers' tokenizer files):
what it reads of the files, decoding with the merged decoder's two branches, where the ONNX files
may be, int8 names, and what it says of a directory it cannot use."""

import json
import shutil
from pathlib import Path
from typing import Any, Dict

import numpy as np
import onnx
import onnx_asr
import pytest

from fixtures.audio import speak_tones
from fixtures.whisper_tones_model import MANIFEST, PIECES, SPECIALS, whisper_tones_model_directory
from fixtures.whisper_tones_optimum import whisper_tones_optimum_directory
from speech_event.errors import ModelError
from speech_event.recognizers.onnx.directory import Runtime
from speech_event.recognizers.onnx.families import family_of
from speech_event.recognizers.whisper.features import whisper_log_mel
from speech_event.recognizers.whisper.forced import score_phrases
from speech_event.recognizers.whisper.model import WhisperModel
from speech_event.recognizers.whisper.optimum_layout import (
    gpt2_byte_decoder,
    load_optimum_manifest,
    load_optimum_pieces,
)
from speech_event.recognizers.whisper.optimum_model import OptimumWhisperModel
from speech_event.recognizers.whisper.recognizer import WhisperRecognizer
from speech_event.recognizers.whisper.tokenizer import WhisperTokenizer

RATE = 16000
SAID = ["go left", "stop", "go to the kitchen", "yego", ""]


def _copy(tmp_path: Path) -> Path:
    return Path(shutil.copytree(whisper_tones_optimum_directory(), tmp_path / "model"))


def _edit_json(directory: Path, name: str, **changes: Any) -> None:
    path = directory / name
    document: Dict[str, Any] = json.loads(path.read_text(encoding="utf-8"))
    for key, value in changes.items():
        if value is None:
            del document[key]
        else:
            document[key] = value
    path.write_text(json.dumps(document), encoding="utf-8")


def test_the_manifest_and_tokens_read_from_transformers_files_are_the_export_layouts() -> None:
    directory = whisper_tones_optimum_directory()
    assert load_optimum_manifest(directory) == MANIFEST
    assert load_optimum_pieces(directory, MANIFEST.vocabulary_size) == PIECES + [s.encode() for s in SPECIALS]


def test_gpt2s_byte_mapping_covers_every_byte_once() -> None:
    decoder = gpt2_byte_decoder()
    assert sorted(decoder.values()) == list(range(256))
    assert decoder["Ġ"] == ord(" ") and decoder["a"] == ord("a") and decoder["Ċ"] == ord("\n")


@pytest.mark.parametrize("said", SAID)
def test_the_optimum_directory_transcribes_as_the_export_directory_does(said: str) -> None:
    audio = speak_tones(said, RATE)
    optimum = WhisperRecognizer(whisper_tones_optimum_directory(), "english").transcribe(audio)
    exported = WhisperRecognizer(whisper_tones_model_directory(), "english").transcribe(audio)
    assert optimum == exported
    assert optimum.text == said


def test_onnx_asr_reads_the_fixture_as_a_whisper_export_of_optimum() -> None:
    # the fixture is the layout onnx-asr loads for Hugging Face's Whisper exports
    model = onnx_asr.load_model("whisper", whisper_tones_optimum_directory())
    assert model.recognize(speak_tones("go to the kitchen", RATE), language="en") == "go to the kitchen"


def test_the_merged_decoder_step_by_step_gives_the_export_decoders_logits() -> None:
    mel = whisper_log_mel(speak_tones("go left", RATE), MANIFEST.mel_bands)
    optimum = OptimumWhisperModel(whisper_tones_optimum_directory()).decoding(mel)
    exported = WhisperModel(whisper_tones_model_directory()).decoding(mel)
    prompt = MANIFEST.prompt("english")
    np.testing.assert_allclose(optimum(prompt), exported(prompt), atol=1e-5)
    forked = optimum.fork()
    go = [PIECES.index(b" g"), PIECES.index(b"o")]
    after_go = exported(go)
    np.testing.assert_allclose(optimum(go), after_go, atol=1e-5)
    # the fork goes on from the prompt, apart from the decoding that went on past it
    np.testing.assert_allclose(forked(go[:1]), after_go[:1], atol=1e-5)


def test_phrases_forced_one_token_a_step_score_as_on_the_export() -> None:
    mel = whisper_log_mel(speak_tones("go left", RATE), MANIFEST.mel_bands)
    prompt = MANIFEST.prompt("english")
    tokenizer = WhisperTokenizer(PIECES, MANIFEST.eot)
    phrases = [tokenizer.encode(text) for text in (" go left", " go", " stop", " go lefts")]
    optimum = score_phrases(
        OptimumWhisperModel(whisper_tones_optimum_directory()).decoding(mel), prompt, phrases, MANIFEST
    )
    exported = score_phrases(
        WhisperModel(whisper_tones_model_directory()).decoding(mel), prompt, phrases, MANIFEST
    )
    assert optimum == [pytest.approx(score, abs=1e-5) for score in exported]
    assert optimum[0] == max(optimum) and np.isfinite(optimum[0])


def test_onnx_files_in_an_onnx_folder_are_found_as_a_hub_repository_keeps_them(tmp_path: Path) -> None:
    directory = _copy(tmp_path)
    (directory / "onnx").mkdir()
    for name in ("encoder_model.onnx", "decoder_model_merged.onnx"):
        (directory / name).rename(directory / "onnx" / name)
    engine = WhisperRecognizer(directory, "english")
    assert engine.transcribe(speak_tones("go left", RATE)).text == "go left"


def test_int8_takes_optimums_int8_names_and_a_directory_of_only_them_runs(tmp_path: Path) -> None:
    directory = _copy(tmp_path)
    for name in ("encoder_model", "decoder_model_merged"):
        (directory / f"{name}.onnx").rename(directory / f"{name}_int8.onnx")
    for runtime in (Runtime(int8=True), Runtime(int8=False)):
        engine = WhisperRecognizer(directory, "english", runtime)
        assert engine.transcribe(speak_tones("stop", RATE)).text == "stop"


def test_its_family_is_whisper_by_the_model_type_of_transformers_config() -> None:
    assert family_of(whisper_tones_optimum_directory(), unrecorded="conformer-transducer") == "whisper"


def test_an_english_only_model_prompts_without_language_or_task_and_serves_english_only(
    tmp_path: Path,
) -> None:
    directory = _copy(tmp_path)
    _edit_json(directory, "generation_config.json", is_multilingual=False)
    manifest = load_optimum_manifest(directory)
    assert manifest.languages == {"english": None} and manifest.transcribe is None
    assert manifest.prompt("english") == [MANIFEST.sot, MANIFEST.no_timestamps]
    with pytest.raises(ModelError, match="has no language token for kinyarwanda"):
        WhisperRecognizer(directory, "kinyarwanda")


def test_without_is_multilingual_the_vocabulary_size_decides_as_whisper_does(tmp_path: Path) -> None:
    directory = _copy(tmp_path)
    _edit_json(directory, "generation_config.json", is_multilingual=None)
    assert load_optimum_manifest(directory).transcribe is None  # 63 tokens: fewer than 51865
    _edit_json(directory, "config.json", vocab_size=51865)
    assert load_optimum_manifest(directory).transcribe == MANIFEST.transcribe


def test_older_exports_keep_the_rules_in_config_json(tmp_path: Path) -> None:
    directory = _copy(tmp_path)
    (directory / "generation_config.json").unlink()
    _edit_json(directory, "config.json", suppress_tokens=[3], begin_suppress_tokens=[MANIFEST.eot, 4])
    manifest = load_optimum_manifest(directory)
    assert manifest.suppress == (3, *MANIFEST.suppress) and manifest.suppress_at_start == (MANIFEST.eot, 4)
    assert manifest.languages == {"english": None}  # and no is_multilingual: 63 tokens


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            lambda d: (d / "added_tokens.json").unlink(),
            r"model: missing added_tokens.json; a Whisper model of",
        ),
        (lambda d: _edit_json(d, "config.json", vocab_size=None), r"config.json: no 'vocab_size'"),
        (
            lambda d: _edit_json(d, "generation_config.json", suppress_tokens=None),
            r"neither generation_config.json nor config.json has 'suppress_tokens'",
        ),
        (
            lambda d: _edit_json(d, "added_tokens.json", **{"<|notimestamps|>": None}),
            r"added_tokens.json: no special token <\|notimestamps\|>",
        ),
        (
            lambda d: _edit_json(d, "vocab.json", **{"a\u3042": 3}),
            r"vocab.json: token 'a\u3042' has '\u3042', not a character of GPT-2's byte-level mapping",
        ),
        (lambda d: (d / "vocab.json").write_text("[1]"), r"vocab.json: not a JSON object"),
        (
            lambda d: _edit_json(d, "added_tokens.json", **{"<|endoftext|>": "end"}),
            r"added_tokens.json: not a map of token texts to integer ids \(invalid literal",
        ),
        (
            lambda d: onnx.save(
                onnx.load(str(whisper_tones_model_directory() / "decoder.onnx")),
                str(d / "decoder_model_merged.onnx"),
            ),
            r"decoder_model_merged.onnx: no past_key_values.\* inputs",
        ),
        (
            lambda d: (d / "encoder_model.onnx").unlink(),
            r"model: missing encoder_model.onnx; a Whisper model of Hugging Face optimum's export holds",
        ),
    ],
    ids=[
        "added-tokens",
        "vocab-size",
        "suppress-tokens",
        "notimestamps",
        "byte-mapping",
        "not-object",
        "non-integer-id",
        "no-cache",
        "encoder",
    ],
)
def test_a_directory_it_cannot_use_names_the_file_and_what_is_missing(
    tmp_path: Path, change: Any, message: str
) -> None:
    directory = _copy(tmp_path)
    change(directory)
    with pytest.raises(ModelError, match=message):
        WhisperRecognizer(directory, "english")
