import os
from pathlib import Path

import pytest
from hypothesis import settings

from fixtures.trained_whisper import converted_once

# CI explores the same examples on every run, so a red build always reproduces; developers'
# runs keep drawing new ones. No deadline: a 2-core CI machine under load is slow, not wrong.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")


@pytest.fixture(scope="session")
def tiny_en(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Whisper tiny.en (trained weights) exported by speech-event export-whisper from faster-whisper's
    directory, once for the whole run: pytest-xdist's workers share the folder above their own."""
    own = tmp_path_factory.getbasetemp()
    return converted_once(own.parent if "PYTEST_XDIST_WORKER" in os.environ else own)
