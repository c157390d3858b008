import os
from pathlib import Path
from typing import Iterator

import pytest
from hypothesis import settings

from fixtures.trained_whisper import SHARED_FOLDER, tiny_en_model_directory

# CI explores the same examples on every run, so a red build always reproduces; developers'
# runs keep drawing new ones. No deadline: a 2-core CI machine under load is slow, not wrong.
settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")


@pytest.fixture(scope="session", autouse=True)
def _trained_whisper_shared(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    """Trained Whisper is converted once a run: pytest-xdist's workers share the folder above their
    own, and the harness's runs inside the tests use it too (fixtures/trained_whisper.py)."""
    own = tmp_path_factory.getbasetemp()
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv(SHARED_FOLDER, str(own.parent if "PYTEST_XDIST_WORKER" in os.environ else own))
        yield


@pytest.fixture(scope="session")
def tiny_en() -> Path:
    """Whisper tiny.en (trained weights) exported by speech-event export-whisper from faster-whisper's
    directory, once for the whole run."""
    return tiny_en_model_directory()
