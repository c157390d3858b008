"""An exported model directory: a directory, not the framework's own file, whose config.json
names the family it was exported from (every family writes one)."""

import json
from pathlib import Path
from typing import Union

from speech_event.errors import ModelError

MANIFEST_FILE = "config.json"


def exported_directory(path: Union[str, Path], framework_suffix: str, export: str) -> Path:
    """``path`` as a model directory; a framework file (``framework_suffix``) gets how to export it
    (``export``: the command, with its extra)."""
    directory = Path(path)
    if directory.suffix == framework_suffix:
        raise ModelError(
            f"{directory} is a {framework_suffix} file, not an exported model directory: export it once with "
            f"'speech-event {export} {directory} OUT_DIR' (needs the 'export' extra), then give OUT_DIR"
        )
    if not directory.is_dir():
        raise ModelError(f"{directory}: no such model directory")
    return directory


def family_of(directory: Path, unrecorded: str) -> str:
    """The family a model directory was exported from (its config.json's family), whatever its
    engine; ``unrecorded`` for a directory written before families were recorded."""
    try:
        document = json.loads((directory / MANIFEST_FILE).read_text(encoding="utf-8"))
        return str(document.get("family", unrecorded))
    except (OSError, ValueError, AttributeError):
        return unrecorded  # the engine says what is wrong with it
