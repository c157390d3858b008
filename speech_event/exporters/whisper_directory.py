"""What speech-event export-whisper writes whatever it reads (an openai-whisper checkpoint or a
faster-whisper directory): the languages a model serves, tokens.txt and config.json."""

import json
from pathlib import Path
from typing import Callable, Dict, List, Optional

from speech_event.errors import ModelError
from speech_event.recognizers.whisper.manifest import (
    MANIFEST_FILE,
    TOKENS_FILE,
    WhisperManifest,
    manifest_json,
    token_lines,
)

# The node's languages and Whisper's codes for them (Whisper has no Kinyarwanda).
WHISPER_CODES = {"english": "en"}


def languages_of(
    multilingual: bool, named: Dict[str, str], language_token: Callable[[str], int]
) -> Dict[str, Optional[int]]:
    """Our language names -> their tokens: English (no token in an English-only model's prompt),
    and those named on the command line (``language_token(code)`` raises for an unknown code)."""
    if not multilingual:
        if set(named) - {"english"}:
            raise ModelError("an English-only checkpoint serves english only; --language cannot add another")
        return {"english": None}
    codes = {**WHISPER_CODES, **named}
    return {language: int(language_token(code)) for language, code in codes.items()}


def write_text_files(out_dir: Path, pieces: List[bytes], manifest: WhisperManifest) -> None:
    """tokens.txt (each token's bytes) and config.json (the manifest) in ``out_dir``."""
    (out_dir / TOKENS_FILE).write_text(token_lines(pieces), encoding="ascii")
    (out_dir / MANIFEST_FILE).write_text(json.dumps(manifest_json(manifest), indent=2), encoding="utf-8")
