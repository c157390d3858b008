"""config.json and tokens.txt of an exported Whisper model directory (speech-event export-whisper).

config.json: the family ("whisper"), the mel bands, the decoder's context, the special tokens the
decoding rules use (sot, eot, no_speech, no_timestamps, timestamp_begin, transcribe), the language
token of each language the node may be set to (none for an English-only checkpoint, whose prompt
has no language and no task), and the tokens the rules suppress (every step; and the first step).
tokens.txt: line i is token i's bytes in base64 (a special token's bytes are its text).
"""

import base64
import binascii
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple

from speech_event.errors import ModelError
from speech_event.recognizers.onnx.directory import MANIFEST_FILE as MANIFEST_FILE
from speech_event.recognizers.onnx.families import register_family

TOKENS_FILE = "tokens.txt"
WHISPER = "whisper"
# model_type in the config.json of Hugging Face's Whisper exports (optimum) and of onnx-asr's own
WHISPER_MODEL_TYPES = ("whisper", "whisper-ort")


@dataclass(frozen=True)
class WhisperManifest:
    """What config.json of a Whisper model directory says: mel bands, context, languages, special tokens."""

    mel_bands: int
    vocabulary_size: int
    text_context: int  # n_text_ctx: the decoder's positions
    sot: int
    eot: int
    no_timestamps: int
    timestamp_begin: int
    languages: Dict[str, Optional[int]]  # our language name -> its token; None: English-only model
    suppress: Tuple[int, ...]  # suppressed at every step (whisper's suppress_tokens "-1")
    suppress_at_start: Tuple[int, ...]  # and at the first (suppress_blank: " " and eot)
    transcribe: Optional[int] = None  # None: an English-only model, no task token
    no_speech: Optional[int] = None

    @property
    def sample_len(self) -> int:
        """At most this many tokens are sampled (whisper's default: half the text context)."""
        return self.text_context // 2

    def prompt(self, language: str) -> List[int]:
        """sot, the language and the task (multilingual models), no timestamps."""
        token = self.languages[language]
        if token is None or self.transcribe is None:
            return [self.sot, self.no_timestamps]
        return [self.sot, token, self.transcribe, self.no_timestamps]


def manifest_json(manifest: WhisperManifest) -> Dict[str, Any]:
    """The config.json document of ``manifest``."""
    return {
        "family": WHISPER,
        "model_type": WHISPER,
        "n_mels": manifest.mel_bands,
        "n_vocab": manifest.vocabulary_size,
        "n_text_ctx": manifest.text_context,
        "sot": manifest.sot,
        "eot": manifest.eot,
        "no_timestamps": manifest.no_timestamps,
        "timestamp_begin": manifest.timestamp_begin,
        "transcribe": manifest.transcribe,
        "no_speech": manifest.no_speech,
        "languages": manifest.languages,
        "suppress_tokens": list(manifest.suppress),
        "suppress_at_start": list(manifest.suppress_at_start),
    }


def _optional_token(document: Dict[str, Any], key: str) -> Optional[int]:
    return None if document.get(key) is None else int(document[key])


def load_whisper_manifest(path: Path) -> WhisperManifest:
    """Read a Whisper model directory's config.json; ModelError says what is missing or wrong."""
    try:
        document = json.loads(path.read_text(encoding="utf-8"))
        return WhisperManifest(
            mel_bands=int(document["n_mels"]),
            vocabulary_size=int(document["n_vocab"]),
            text_context=int(document["n_text_ctx"]),
            sot=int(document["sot"]),
            eot=int(document["eot"]),
            no_timestamps=int(document["no_timestamps"]),
            timestamp_begin=int(document["timestamp_begin"]),
            languages={str(k): None if v is None else int(v) for k, v in dict(document["languages"]).items()},
            suppress=tuple(int(t) for t in document["suppress_tokens"]),
            suppress_at_start=tuple(int(t) for t in document["suppress_at_start"]),
            transcribe=_optional_token(document, "transcribe"),
            no_speech=_optional_token(document, "no_speech"),
        )
    except OSError as problem:
        raise ModelError(f"{path}: cannot read the model's config: {problem.strerror}") from None
    except (ValueError, KeyError, TypeError) as problem:
        raise ModelError(
            f"{path}: not a usable Whisper model config ({problem!r}); speech-event export-whisper writes "
            "n_mels, n_vocab, n_text_ctx, the special tokens, languages and the suppressed tokens"
        ) from None


def token_lines(pieces: Sequence[bytes]) -> str:
    """tokens.txt's text: each token's bytes in base64, one a line."""
    return "".join(base64.b64encode(piece).decode("ascii") + "\n" for piece in pieces)


def load_tokens(path: Path) -> List[bytes]:
    """Read tokens.txt: each token's bytes, by id; ModelError when it is not such a file."""
    try:
        lines = path.read_text(encoding="ascii").splitlines()
        return [base64.b64decode(line, validate=True) for line in lines]
    except OSError as problem:
        raise ModelError(f"{path}: cannot read the tokens: {problem.strerror}") from None
    except (ValueError, binascii.Error):
        raise ModelError(f"{path}: not a tokens file (one token's bytes in base64 a line)") from None


def text_of(tokens: Sequence[int], pieces: Sequence[bytes], timestamp_begin: int) -> str:
    """Whisper's tokenizer.decode: timestamps left out, bytes joined, invalid UTF-8 replaced."""
    joined = b"".join(pieces[token] for token in tokens if token < timestamp_begin)
    return joined.decode("utf-8", errors="replace")


def whisper_family_of(directory: Path, document: Dict[str, Any]) -> Optional[str]:
    """whisper for a directory of Hugging Face's or onnx-asr's Whisper exports, which do not record
    the family (their config.json's model_type says it); None for any other."""
    return WHISPER if document.get("model_type") in WHISPER_MODEL_TYPES else None


register_family(whisper_family_of)
