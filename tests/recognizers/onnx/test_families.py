"""Which family a model directory holds (speech_event/recognizers/onnx/families.py): the shared
code knows no family; each registers its test of a directory when its manifest module is imported."""

import json
import subprocess
import sys
from pathlib import Path

from fixtures.paths import ROOT


def test_importing_the_registry_alone_registers_every_family(tmp_path: Path) -> None:
    # A fresh interpreter that imports nothing but the registry: the recognizers package, which
    # Python initialises first, imports every family's manifest, so each has registered.
    for family, model_type in (("whisper", "whisper"), ("parakeet", "nemo-conformer-tdt")):
        (tmp_path / family).mkdir()
        (tmp_path / family / "config.json").write_text(json.dumps({"model_type": model_type}))
    code = (
        "import sys; from pathlib import Path; "
        "from speech_event.recognizers.onnx.families import family_of; "
        "print([family_of(Path(sys.argv[1]) / name, 'unrecorded') for name in ('whisper', 'parakeet', 'none')])"
    )
    result = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path)], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert result.stdout == "['whisper', 'parakeet', 'unrecorded']\n"
