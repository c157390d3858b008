"""The export tool's own steps (NeMo itself is not installed in CI; bench/nemo_parity.py runs it)."""

from pathlib import Path

import pytest

from fixtures.nemo_config import PREPROCESSOR
from speech_event.asr.errors import ModelError
from speech_event.asr.export_nemo import manifest_from_preprocessor, vocabulary_lines
from speech_event.asr.features import FeatureSettings
from speech_event.asr.manifest import Manifest
from tests.application import run_application

ROOT = Path(__file__).resolve().parents[1]


def test_the_conformer_preprocessor_config_becomes_the_engine_features() -> None:
    assert manifest_from_preprocessor(PREPROCESSOR, 10) == Manifest(FeatureSettings(), 10)


def test_n_fft_left_out_is_the_next_power_of_two_of_the_window_as_in_nemo() -> None:
    preprocessor = {**PREPROCESSOR, "n_fft": None}
    assert manifest_from_preprocessor(preprocessor, None).features.n_fft == 512


def test_a_preprocessor_the_engine_does_not_implement_is_refused_by_name() -> None:
    with pytest.raises(ModelError) as error:
        manifest_from_preprocessor({**PREPROCESSOR, "window": "hamming"}, 10)
    assert (
        str(error.value)
        == "preprocessor window = 'hamming' is not supported; the engine computes window = 'hann'"
    )


def test_the_vocabulary_puts_the_blank_last() -> None:
    assert vocabulary_lines(["\u2581mu", "raho"]) == "\u2581mu 0\nraho 1\n<blk> 2\n"


def test_without_nemo_the_export_says_how_to_get_it(tmp_path: Path) -> None:
    result = run_application("export-nemo", "m.nemo", str(tmp_path))
    assert result.returncode == 2
    assert result.stderr == (
        "error: export-nemo needs NeMo: pip install 'speech-event[export]' (nemo_toolkit and torch); "
        "only for exporting, never on the robot\n"
    )
