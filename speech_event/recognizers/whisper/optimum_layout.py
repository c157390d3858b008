"""What the Whisper engine reads of a Whisper model as Hugging Face optimum exports it (the
onnx-community/whisper-* repositories, what speech-event pull writes for them): the WhisperManifest
and each token's bytes, from config.json, generation_config.json, vocab.json and added_tokens.json.

- config.json (transformers' WhisperConfig): ``num_mel_bins``, ``vocab_size``,
  ``max_target_positions``;
- added_tokens.json: the special tokens by their text (``<|startoftranscript|>``, ``<|en|>``, ...);
  the first timestamp is ``<|0.00|>``, or the token after ``<|notimestamps|>`` when not listed;
- Whisper's rules (whisper.decoding with suppress_tokens "-1"): ``suppress_tokens`` and
  ``begin_suppress_tokens`` of generation_config.json (of config.json in older exports), with the
  task, start and no-speech tokens added as whisper adds them;
- multilingual: generation_config.json's ``is_multilingual``, else as whisper decides it (51865
  tokens or more); an English-only model's prompt has no language and no task;
- languages: English (``<|en|>``), and Kinyarwanda where the tokenizer has ``<|rw|>`` (Whisper has
  none; a checkpoint fine-tuned for Kinyarwanda under that code does);
- vocab.json: each token's text in GPT-2's byte-to-character mapping (byte-level BPE).
"""

import json
from pathlib import Path
from typing import Any, Dict, List, Optional, Tuple

from speech_event.errors import ModelError
from speech_event.recognizers.whisper.manifest import MANIFEST_FILE, WhisperManifest

VOCABULARY_FILE = "vocab.json"
ADDED_TOKENS_FILE = "added_tokens.json"
GENERATION_FILE = "generation_config.json"
MULTILINGUAL_VOCABULARY = 51865  # whisper's ModelDimensions: is_multilingual = n_vocab >= 51865
# The special tokens whisper's rules suppress besides the non-speech ones (its _get_suppress_tokens),
# those the tokenizer has
SUPPRESSED_SPECIALS = (
    "<|transcribe|>",
    "<|translate|>",
    "<|startoftranscript|>",
    "<|startofprev|>",
    "<|startoflm|>",
)
NO_SPEECH_TOKENS = ("<|nospeech|>", "<|nocaptions|>")  # large-v3's name, then the others'
LANGUAGE_TOKENS = {"english": "<|en|>", "kinyarwanda": "<|rw|>"}
OPTIMUM_FILES = f"{MANIFEST_FILE}, {GENERATION_FILE}, {VOCABULARY_FILE} and {ADDED_TOKENS_FILE}"


def gpt2_byte_decoder() -> Dict[str, int]:
    """GPT-2's byte-level BPE writes each byte as a printable character: the printable Latin-1
    bytes as themselves, the others as the characters from U+0100 on, in byte order."""
    printable = [
        *range(ord("!"), ord("~") + 1),
        *range(ord("¡"), ord("¬") + 1),
        *range(ord("®"), ord("ÿ") + 1),
    ]
    others = [byte for byte in range(256) if byte not in printable]
    decoder = {chr(byte): byte for byte in printable}
    decoder.update({chr(256 + index): byte for index, byte in enumerate(others)})
    return decoder


def _json(path: Path, required: bool) -> Dict[str, Any]:
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        if required:
            raise ModelError(
                f"{path.parent}: missing {path.name}; a Whisper model of Hugging Face optimum's export "
                f"holds encoder_model.onnx, decoder_model_merged.onnx, {OPTIMUM_FILES}"
            ) from None
        return {}
    except OSError as problem:
        raise ModelError(f"{path}: cannot read it: {problem.strerror}") from None
    except ValueError as problem:
        raise ModelError(f"{path}: not JSON ({problem})") from None
    if not isinstance(document, dict):
        raise ModelError(f"{path}: not a JSON object")
    return document


def _token_ids(path: Path) -> Dict[str, int]:
    """vocab.json or added_tokens.json: each token's text and its id."""
    try:
        return {str(text): int(token) for text, token in _json(path, required=True).items()}
    except (TypeError, ValueError) as problem:
        raise ModelError(f"{path}: not a map of token texts to integer ids ({problem})") from None


def _key(path: Path, document: Dict[str, Any], key: str) -> Any:
    if key not in document:
        raise ModelError(f"{path}: no {key!r}; transformers' Whisper config has it")
    return document[key]


def _token(path: Path, added: Dict[str, int], text: str) -> int:
    if text not in added:
        raise ModelError(f"{path}: no special token {text}; Whisper's tokenizer has it")
    return int(added[text])


def _rules(
    config: Dict[str, Any], generation: Dict[str, Any], directory: Path
) -> Tuple[List[int], List[int]]:
    """suppress_tokens and begin_suppress_tokens: generation_config.json's, else config.json's."""
    found = []
    for key in ("suppress_tokens", "begin_suppress_tokens"):
        source = generation if key in generation else config
        if source.get(key) is None:
            raise ModelError(
                f"{directory}: neither {GENERATION_FILE} nor {MANIFEST_FILE} has {key!r}, which Whisper's "
                "decoding rules need"
            )
        found.append([int(token) for token in source[key]])
    return found[0], found[1]


def load_optimum_manifest(directory: Path) -> WhisperManifest:
    """The WhisperManifest of an optimum export in ``directory``; ModelError names the file and key."""
    config_path, added_path = directory / MANIFEST_FILE, directory / ADDED_TOKENS_FILE
    config = _json(config_path, required=True)
    added = _token_ids(added_path)
    try:
        vocabulary_size = int(_key(config_path, config, "vocab_size"))
        mel_bands = int(_key(config_path, config, "num_mel_bins"))
        text_context = int(_key(config_path, config, "max_target_positions"))
    except (TypeError, ValueError) as problem:
        raise ModelError(f"{config_path}: not a usable Whisper config ({problem})") from None
    generation = _json(directory / GENERATION_FILE, required=False)
    suppress, suppress_at_start = _rules(config, generation, directory)
    no_timestamps = _token(added_path, added, "<|notimestamps|>")
    no_speech = next((added[text] for text in NO_SPEECH_TOKENS if text in added), None)
    specials = [added[text] for text in SUPPRESSED_SPECIALS if text in added]
    multilingual = bool(generation.get("is_multilingual", vocabulary_size >= MULTILINGUAL_VOCABULARY))
    languages: Dict[str, Optional[int]] = {"english": None}
    if multilingual:
        languages = {name: added[text] for name, text in LANGUAGE_TOKENS.items() if text in added}
        languages["english"] = _token(added_path, added, LANGUAGE_TOKENS["english"])
    return WhisperManifest(
        mel_bands=mel_bands,
        vocabulary_size=vocabulary_size,
        text_context=text_context,
        sot=_token(added_path, added, "<|startoftranscript|>"),
        eot=_token(added_path, added, "<|endoftext|>"),
        no_timestamps=no_timestamps,
        timestamp_begin=added.get("<|0.00|>", no_timestamps + 1),
        languages=languages,
        suppress=tuple(sorted({*suppress, *specials, *([] if no_speech is None else [no_speech])})),
        suppress_at_start=tuple(suppress_at_start),
        transcribe=_token(added_path, added, "<|transcribe|>") if multilingual else None,
        no_speech=no_speech,
    )


def load_optimum_pieces(directory: Path, vocabulary_size: int) -> List[bytes]:
    """Each token's bytes, by id: vocab.json's through GPT-2's byte mapping, a special token's as its
    text; empty for an id neither file has (the timestamps older tokenizers do not list)."""
    path = directory / VOCABULARY_FILE
    texts = {token: (text, True) for text, token in _token_ids(path).items()}
    added = _token_ids(directory / ADDED_TOKENS_FILE)
    texts.update({token: (text, False) for text, token in added.items()})
    decoder = gpt2_byte_decoder()
    pieces = [b""] * vocabulary_size
    for token, (text, byte_level) in texts.items():
        if not 0 <= token < vocabulary_size:
            raise ModelError(
                f"{path.parent}: token {text!r} has id {token}, beyond the model's {vocabulary_size}"
            )
        pieces[token] = _bytes_of(path, text, decoder) if byte_level else text.encode("utf-8")
    return pieces


def _bytes_of(path: Path, text: str, decoder: Dict[str, int]) -> bytes:
    try:
        return bytes(decoder[character] for character in text)
    except KeyError as problem:
        raise ModelError(
            f"{path}: token {text!r} has {problem.args[0]!r}, not a character of GPT-2's byte-level mapping"
        ) from None


def is_optimum_directory(directory: Path) -> bool:
    """Whether ``directory`` holds optimum's tokenizer (vocab.json), not export-whisper's tokens.txt."""
    return (directory / VOCABULARY_FILE).is_file()
