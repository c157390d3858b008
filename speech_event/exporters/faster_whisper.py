"""A faster-whisper model directory (CTranslate2's Whisper: model.bin, config.json, and the
vocabulary: vocabulary.json, vocabulary.txt or tokenizer.json) to the directory the Whisper engine
loads, with numpy and onnx alone (``speech-event export-whisper DIR OUT_DIR``).

- model.bin (ctranslate2.py): the WhisperSpec's variables, float32 however stored. CTranslate2
  fuses self-attention's query, key and value into one matrix (``linear_0``, the key's bias zero)
  and cross-attention's key and value (``linear_1``); the output projection is an alias of the
  token embedding.
- the vocabulary: each token's text in GPT-2's byte-level characters (special tokens as their
  text), a token an id; tokens.txt gets their bytes.
- config.json: ``suppress_ids`` (whisper's non-speech tokens) and ``suppress_ids_begin`` (" " and
  end of text), the rules CTranslate2 applies with suppress_tokens -1 and suppress_blank. The
  engine's config.json suppresses those, and the special tokens whisper adds to them (task, start,
  previous text, language model, no speech) where the vocabulary has them.
"""

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

from speech_event.errors import ModelError
from speech_event.exporters.ctranslate2 import ModelBin, read_model_bin
from speech_event.exporters.whisper_directory import languages_of, write_text_files
from speech_event.exporters.whisper_weights import (
    LAYER_NORM_EPSILON,
    DecoderBlock,
    Dense,
    EncoderBlock,
    Norm,
    WhisperWeights,
)
from speech_event.recognizers.whisper.manifest import WhisperManifest
from speech_event.recognizers.whisper.model import DECODER_FILE, ENCODER_FILE
from speech_event.recognizers.whisper.optimum_layout import (
    NO_SPEECH_TOKENS,
    SUPPRESSED_SPECIALS,
    gpt2_byte_decoder,
)

MODEL_FILE = "model.bin"
CONFIG_FILE = "config.json"
VOCABULARY_FILES = ("vocabulary.json", "vocabulary.txt", "tokenizer.json")
WHISPER_SPEC = "WhisperSpec"
# Each WhisperSpec revision CTranslate2 has written: between them its config.json and activation
# codes changed, not the variables read here
SPEC_REVISIONS = (1, 2, 3)
MULTILINGUAL_VOCABULARY = 51865  # whisper's ModelDimensions: is_multilingual = n_vocab >= 51865
FASTER_WHISPER_DIRECTORY = (
    f"a faster-whisper (CTranslate2) model directory holds {MODEL_FILE}, {CONFIG_FILE} and "
    f"{', '.join(VOCABULARY_FILES[:-1])} or {VOCABULARY_FILES[-1]}"
)


def is_faster_whisper_directory(path: Path) -> bool:
    """Whether ``path`` is a directory with CTranslate2's model.bin."""
    return (path / MODEL_FILE).is_file()


def _dense(model: ModelBin, scope: str) -> Dense:
    return Dense(model.float32(f"{scope}/weight"), model.float32(f"{scope}/bias"))


def _norm(model: ModelBin, scope: str) -> Norm:
    return Norm(model.float32(f"{scope}/gamma"), model.float32(f"{scope}/beta"))


def _layers(model: ModelBin, scope: str) -> int:
    count = 0
    while any(name.startswith(f"{scope}/layer_{count}/") for name in model.variables):
        count += 1
    if count == 0:
        raise ModelError(f"{model.path}: no {scope}/layer_0; a Whisper model of CTranslate2 has its blocks")
    return count


def whisper_weights(model: ModelBin, layer_norm_epsilon: float = LAYER_NORM_EPSILON) -> WhisperWeights:
    """The weights of a WhisperSpec model.bin, float32."""
    if model.spec != WHISPER_SPEC:
        raise ModelError(
            f"{model.path}: a CTranslate2 {model.spec or 'unnamed'} model, not Whisper ({WHISPER_SPEC})"
        )
    if model.revision not in SPEC_REVISIONS:
        raise ModelError(
            f"{model.path}: {WHISPER_SPEC} revision {model.revision}; revisions "
            f"{SPEC_REVISIONS[0]} to {SPEC_REVISIONS[-1]} can be read (a later CTranslate2 wrote it)"
        )
    encoder_blocks = [
        EncoderBlock(
            attention_norm=_norm(model, f"{scope}/self_attention/layer_norm"),
            qkv=_dense(model, f"{scope}/self_attention/linear_0"),
            attention_out=_dense(model, f"{scope}/self_attention/linear_1"),
            mlp_norm=_norm(model, f"{scope}/ffn/layer_norm"),
            mlp_in=_dense(model, f"{scope}/ffn/linear_0"),
            mlp_out=_dense(model, f"{scope}/ffn/linear_1"),
        )
        for scope in (f"encoder/layer_{index}" for index in range(_layers(model, "encoder")))
    ]
    decoder_blocks = [
        DecoderBlock(
            attention_norm=_norm(model, f"{scope}/self_attention/layer_norm"),
            qkv=_dense(model, f"{scope}/self_attention/linear_0"),
            attention_out=_dense(model, f"{scope}/self_attention/linear_1"),
            cross_norm=_norm(model, f"{scope}/attention/layer_norm"),
            cross_query=_dense(model, f"{scope}/attention/linear_0"),
            cross_kv=_dense(model, f"{scope}/attention/linear_1"),
            cross_out=_dense(model, f"{scope}/attention/linear_2"),
            mlp_norm=_norm(model, f"{scope}/ffn/layer_norm"),
            mlp_in=_dense(model, f"{scope}/ffn/linear_0"),
            mlp_out=_dense(model, f"{scope}/ffn/linear_1"),
        )
        for scope in (f"decoder/layer_{index}" for index in range(_layers(model, "decoder")))
    ]
    return WhisperWeights(
        conv1=_dense(model, "encoder/conv1"),
        conv2=_dense(model, "encoder/conv2"),
        audio_positions=model.float32("encoder/position_encodings/encodings"),
        encoder_blocks=encoder_blocks,
        encoder_norm=_norm(model, "encoder/layer_norm"),
        encoder_heads=model.integer("encoder/num_heads"),
        embedding=model.float32("decoder/embeddings/weight"),
        text_positions=model.float32("decoder/position_encodings/encodings"),
        decoder_blocks=decoder_blocks,
        decoder_norm=_norm(model, "decoder/layer_norm"),
        decoder_heads=model.integer("decoder/num_heads"),
        layer_norm_epsilon=layer_norm_epsilon,
    )


def _json(path: Path) -> Any:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except OSError as problem:
        raise ModelError(f"{path}: cannot read it: {problem.strerror}") from None
    except ValueError as problem:
        raise ModelError(f"{path}: not JSON ({problem})") from None


def read_config(path: Path) -> Dict[str, Any]:
    """config.json of CTranslate2's Whisper: the suppressed tokens (and a layer_norm_epsilon, if any)."""
    if not path.is_file():
        raise ModelError(f"{path.parent}: missing {path.name}; {FASTER_WHISPER_DIRECTORY}")
    document = _json(path)
    if not isinstance(document, dict):
        raise ModelError(f"{path}: not a JSON object")
    for key in ("suppress_ids", "suppress_ids_begin"):
        values = document.get(key)
        if not isinstance(values, list) or not all(isinstance(token, int) for token in values):
            raise ModelError(
                f"{path}: no list of token ids {key!r}; CTranslate2's Whisper config has suppress_ids "
                "and suppress_ids_begin, which Whisper's decoding rules need"
            )
    return document


def read_vocabulary(directory: Path) -> Tuple[List[str], Path]:
    """Each token's text by id, and the file read: vocabulary.json (a list), vocabulary.txt (a token
    a line) or tokenizer.json (the BPE model's vocabulary and the added tokens), the first found.
    An id tokenizer.json does not name (it lists no timestamps) has no text."""
    json_path, text_path, tokenizer_path = (directory / name for name in VOCABULARY_FILES)
    if json_path.is_file():
        tokens = _json(json_path)
        if not isinstance(tokens, list) or not all(isinstance(token, str) for token in tokens):
            raise ModelError(f"{json_path}: not a JSON list of token texts")
        return tokens, json_path
    if text_path.is_file():
        try:
            lines = text_path.read_text(encoding="utf-8").split("\n")
        except (OSError, UnicodeDecodeError) as problem:
            raise ModelError(f"{text_path}: cannot read it as UTF-8 text ({problem})") from None
        return (lines[:-1] if lines[-1] == "" else lines), text_path  # each token ends in a newline
    if tokenizer_path.is_file():
        return _tokenizer_vocabulary(tokenizer_path), tokenizer_path
    raise ModelError(f"{directory}: no vocabulary; {FASTER_WHISPER_DIRECTORY}")


def _tokenizer_vocabulary(path: Path) -> List[str]:
    document = _json(path)
    try:
        ids = {str(text): int(token) for text, token in document["model"]["vocab"].items()}
        ids.update({str(added["content"]): int(added["id"]) for added in document.get("added_tokens", [])})
    except (KeyError, TypeError, ValueError, AttributeError) as problem:
        raise ModelError(
            f"{path}: not a tokenizer with a vocabulary (model.vocab, added_tokens): {problem!r}"
        ) from None
    texts = [""] * (max(ids.values()) + 1)
    for text, token in ids.items():
        texts[token] = text
    return texts


def token_pieces(tokens: List[str], source: Path) -> List[bytes]:
    """Each token's bytes: its text through GPT-2's byte-level mapping (a special token's text
    is printable ASCII, which maps to itself)."""
    decoder = gpt2_byte_decoder()
    pieces = []
    for token, text in enumerate(tokens):
        try:
            pieces.append(bytes(decoder[character] for character in text))
        except KeyError as problem:
            raise ModelError(
                f"{source}: token {token} {text!r} has {problem.args[0]!r}, not a character of GPT-2's "
                "byte-level mapping (Whisper's tokenizer)"
            ) from None
    return pieces


def _special(ids: Dict[str, int], text: str, source: Path) -> int:
    if text not in ids:
        raise ModelError(f"{source}: no special token {text}; Whisper's tokenizer has it")
    return ids[text]


def whisper_manifest(
    weights: WhisperWeights,
    tokens: List[str],
    config: Dict[str, Any],
    named: Dict[str, str],
    source: Path,
) -> WhisperManifest:
    """What the engine needs: the special tokens by their text in the vocabulary (``source``), the
    languages (``named``: --language's), and whisper's rules from config.json's token lists."""
    ids = {text: token for token, text in enumerate(tokens) if text}
    vocabulary_size = int(weights.embedding.shape[0])
    multilingual = vocabulary_size >= MULTILINGUAL_VOCABULARY
    no_timestamps = _special(ids, "<|notimestamps|>", source)
    no_speech: Optional[int] = next((ids[text] for text in NO_SPEECH_TOKENS if text in ids), None)
    specials = {ids[text] for text in SUPPRESSED_SPECIALS if text in ids}
    try:
        languages = languages_of(multilingual, named, lambda code: ids[f"<|{code}|>"])
    except KeyError as problem:
        raise ModelError(f"{source}: no language token {problem.args[0]}") from None
    return WhisperManifest(
        mel_bands=weights.mel_bands,
        vocabulary_size=vocabulary_size,
        text_context=int(weights.text_positions.shape[0]),
        sot=_special(ids, "<|startoftranscript|>", source),
        eot=_special(ids, "<|endoftext|>", source),
        no_timestamps=no_timestamps,
        timestamp_begin=no_timestamps + 1,  # as CTranslate2 and whisper number them
        languages=languages,
        suppress=tuple(
            sorted({*config["suppress_ids"], *specials, *([] if no_speech is None else [no_speech])})
        ),
        suppress_at_start=tuple(config["suppress_ids_begin"]),
        transcribe=_special(ids, "<|transcribe|>", source) if multilingual else None,
        no_speech=no_speech,
    )


@dataclass(frozen=True)
class FasterWhisperModel:
    """A faster-whisper directory, read: the weights, the engine's manifest and each token's bytes."""

    weights: WhisperWeights
    manifest: WhisperManifest
    pieces: List[bytes]


def read_faster_whisper(directory: Path, named: Dict[str, str]) -> FasterWhisperModel:
    """Read a faster-whisper directory; ``named``: --language's codes (a multilingual model)."""
    config = read_config(directory / CONFIG_FILE)
    epsilon = config.get("layer_norm_epsilon")  # CTranslate2's LayerNorm takes it from there
    weights = whisper_weights(
        read_model_bin(directory / MODEL_FILE), LAYER_NORM_EPSILON if epsilon is None else float(epsilon)
    )
    tokens, source = read_vocabulary(directory)
    rows = int(weights.embedding.shape[0])
    if len(tokens) > rows:
        raise ModelError(
            f"{source}: {len(tokens)} tokens, but {directory / MODEL_FILE} embeds {rows}: not of one model"
        )
    tokens = tokens + [""] * (rows - len(tokens))
    manifest = whisper_manifest(weights, tokens, config, named, source)
    return FasterWhisperModel(weights, manifest, token_pieces(tokens, source))


def export_faster_whisper(directory: Path, out_dir: Path, named: Dict[str, str]) -> WhisperManifest:
    """Write the engine's directory for the faster-whisper model in ``directory`` to ``out_dir``."""
    model = read_faster_whisper(directory, named)
    try:
        from speech_event.exporters.graph_files import save_graph
        from speech_event.exporters.whisper_graphs import decoder_graph, encoder_graph
    except ImportError:
        # not a dependency of the node: the robot runs the files, it does not write them
        raise ModelError(
            "export-whisper writes the ONNX graphs with the onnx package: pip install onnx (a "
            "faster-whisper directory needs neither torch nor openai-whisper)"
        ) from None
    out_dir.mkdir(parents=True, exist_ok=True)
    save_graph(encoder_graph(model.weights), out_dir / ENCODER_FILE)
    save_graph(decoder_graph(model.weights), out_dir / DECODER_FILE)
    write_text_files(out_dir, model.pieces, model.manifest)
    return model.manifest
