"""Which family an exported model directory holds, told without knowing any family.

Each family registers a test of a directory when its manifest module is imported (nemo/manifest.py,
whisper/manifest.py); ``speech_event.recognizers`` imports every family's, and Python runs that
package's ``__init__`` before any module under it, so every family has registered before anyone
can ask. A new family registers its own test: this module does not change.
"""

import json
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional

from speech_event.recognizers.onnx.directory import MANIFEST_FILE

# A family's test: the family of a directory whose config.json (a JSON object, {} without one)
# does not record it, if the directory is that family's; None otherwise. No two families claim
# the same directory, so the order they registered in does not matter.
FamilyTest = Callable[[Path, Dict[str, Any]], Optional[str]]

_TESTS: List[FamilyTest] = []


def register_family(test: FamilyTest) -> None:
    """A family's test of a directory, asked by ``family_of`` from now on."""
    _TESTS.append(test)


def family_of(directory: Path, unrecorded: str) -> str:
    """The family of a model directory, whatever its engine: its config.json's family; for one that
    does not record it, the family whose test claims it; ``unrecorded`` when none does."""
    try:
        document = json.loads((directory / MANIFEST_FILE).read_text(encoding="utf-8"))
    except FileNotFoundError:
        document = {}
    except (OSError, ValueError):
        return unrecorded  # the engine says what is wrong with it
    if not isinstance(document, dict):
        return unrecorded
    if "family" in document:
        return str(document["family"])
    claimed = (test(directory, document) for test in _TESTS)  # lazily: NeMo's may open the joint
    return next((family for family in claimed if family is not None), unrecorded)
