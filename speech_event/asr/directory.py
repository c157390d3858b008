"""What an engine is given must be an exported model directory, not the framework's own file."""

from pathlib import Path
from typing import Union

from speech_event.asr.errors import ModelError


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
