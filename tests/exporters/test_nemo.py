"""The export tool's own steps (NeMo itself is not installed in CI; bench/parity/nemo_parity.py runs it)."""

from pathlib import Path

import pytest

from fixtures.application import run_application
from fixtures.nemo_config import PREPROCESSOR
from speech_event.errors import ModelError
from speech_event.exporters.nemo import feature_settings, manifest_for, vocabulary_lines
from speech_event.recognizers.nemo.features import FeatureSettings
from speech_event.recognizers.nemo.manifest import Manifest

CONFORMER = {
    "preprocessor": PREPROCESSOR,
    "encoder": {"subsampling": "striding", "subsampling_factor": 4},
    "decoding": {"strategy": "greedy_batch", "greedy": {"max_symbols": 10}},
}
# Parakeet-TDT's sections (fastconformer_hybrid_tdt_ctc_bpe.yaml, resolved): FastConformer's 8x
# depthwise-striding subsampling, 128 mel bands, TDT decoding.
FAST_CONFORMER_TDT = {
    "preprocessor": {**PREPROCESSOR, "features": 128},
    "encoder": {"subsampling": "dw_striding", "subsampling_factor": 8},
    "decoding": {
        "strategy": "greedy_batch",
        "model_type": "tdt",
        "durations": [0, 1, 2, 3, 4],
        "greedy": {"max_symbols": 10},
    },
}


def test_the_conformer_transducer_config_becomes_its_manifest() -> None:
    assert manifest_for(CONFORMER, hybrid=False, ctc=False) == Manifest(FeatureSettings(), 10)


def test_a_fast_conformer_tdt_is_the_parakeet_family_with_its_subsampling_bands_and_durations() -> None:
    manifest = manifest_for(FAST_CONFORMER_TDT, hybrid=True, ctc=False)
    assert manifest == Manifest(
        FeatureSettings(mel_bands=128),
        max_symbols_per_step=10,
        decoding="nemo-conformer-tdt",
        family="parakeet",
        subsampling_factor=8,
        durations=(0, 1, 2, 3, 4),
    )


def test_a_hybrid_model_s_ctc_head_is_ctc_decoding_without_durations() -> None:
    manifest = manifest_for(FAST_CONFORMER_TDT, hybrid=True, ctc=True)
    assert (manifest.decoding, manifest.family, manifest.durations) == ("nemo-conformer-ctc", "parakeet", ())


def test_a_fast_conformer_rnnt_is_parakeet_and_the_family_can_be_named() -> None:
    fast_rnnt = {**CONFORMER, "encoder": {"subsampling": "dw_striding", "subsampling_factor": 8}}
    assert manifest_for(fast_rnnt, hybrid=False, ctc=False).family == "parakeet"
    assert (
        manifest_for(fast_rnnt, False, False, family="conformer-transducer").family == "conformer-transducer"
    )


def test_a_tdt_config_without_durations_is_refused() -> None:
    config = {**CONFORMER, "decoding": {"model_type": "tdt"}}
    with pytest.raises(ModelError) as error:
        manifest_for(config, hybrid=False, ctc=False)
    assert str(error.value) == "a TDT model whose config has no decoding.durations: cannot tell its durations"


def test_n_fft_left_out_is_the_next_power_of_two_of_the_window_as_in_nemo() -> None:
    preprocessor = {**PREPROCESSOR, "n_fft": None}
    assert feature_settings(preprocessor).n_fft == 512


def test_a_preprocessor_the_engine_does_not_implement_is_refused_by_name() -> None:
    with pytest.raises(ModelError) as error:
        feature_settings({**PREPROCESSOR, "window": "hamming"})
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
