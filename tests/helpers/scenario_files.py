"""The scenario files: those on trained weights (tox env ``real``), the others (hermetic: fake,
tones models, pocketsphinx), and among those the ones written for the fake engine in the tones
voice (the others name the engine they need): every engine that transcribes the tones voice passes
those."""

from pathlib import Path
from typing import List

from harness.catalog import TRAINED_MODELS
from harness.scenario import load_scenario
from speech_event.config import SpeechEventConfig
from tests.helpers.paths import ROOT

ALL_SCENARIOS = sorted((ROOT / "scenarios").glob("*.toml"))


def _on_trained_weights(path: Path) -> bool:
    return load_scenario(path, SpeechEventConfig()).recognizer in TRAINED_MODELS


TRAINED_SCENARIOS = [path for path in ALL_SCENARIOS if _on_trained_weights(path)]
SCENARIOS = [path for path in ALL_SCENARIOS if not _on_trained_weights(path)]


def _for_the_fake_in_tones(path: Path) -> bool:
    """Written for the fake in the tones voice, and not about one engine's partial texts or its
    transcript messages (which name the engine)."""
    scenario = load_scenario(path, SpeechEventConfig())
    engine_specific = scenario.expected_partials is not None or scenario.expected_transcripts is not None
    return (scenario.voice, scenario.recognizer) == ("tones", "fake") and not engine_specific


TONES_SCENARIOS = [path for path in SCENARIOS if _for_the_fake_in_tones(path)]


def shard(paths: List[Path], index: int, count: int) -> List[Path]:
    """Every ``count``-th scenario from ``index``: the ROS replays run as ``count`` tests, which
    pytest-xdist's workers take side by side (each replay has its own roscore)."""
    return paths[index::count]
