import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from fixtures.application import run_application
from fixtures.paths import ROOT
from speech_event.config import (
    DECIDING_SPECULATION_GAP,
    GRAMMAR_END_OF_SPEECH,
    SPECULATION_GAP,
    ConfigError,
    SpeechEventConfig,
    apply_overrides,
    end_of_speech_chosen,
    end_of_speech_seconds,
    ends_at_end_of_speech,
    format_config,
    load_config,
    parse_config,
    speculation_gap_seconds,
)


def test_a_file_sets_keys_in_every_accepted_form_and_leaves_the_rest_at_defaults() -> None:
    text = (
        "# Speech Event\n"
        "language\tKinyarwanda\n"
        "verbose_mode   true\n"
        "sample_rate = 16000   # the driver's rate\n"
        "speechPausePeriod=0.8\n"
        "rw_model_path /models/rw#1\n"
        "\n"
    )
    assert parse_config(text) == SpeechEventConfig(
        language="kinyarwanda",
        verbose_mode=True,
        sample_rate=16000,
        speech_pause_period=0.8,
        rw_model_path="/models/rw#1",
    )


def test_the_robot_camel_case_keys_are_aliases() -> None:
    config = parse_config(
        "verboseMode true\nsampleRate 44100\nspeechPausePeriod 2.5\nmaxUtteranceLength 5\n"
        "confidence 0.4\nheartbeatMsgPeriod 30\n"
    )
    assert (config.verbose_mode, config.sample_rate, config.speech_pause_period) == (True, 44100, 2.5)
    assert (config.max_utterance_length, config.confidence, config.heartbeat_msg_period) == (5.0, 0.4, 30.0)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "sample_rate abc",
            "f.ini:1: key 'sample_rate': value 'abc' is not an integer; "
            "allowed: an integer number of Hz from 8000 to 192000",
        ),
        (
            "language kinyarwanda\nlanguage french",
            "f.ini:2: key 'language' is set again (first set on line 1); set each key once",
        ),
        (
            "\nlanguage french",
            "f.ini:2: key 'language': value 'french' is not one of the choices; "
            "allowed: kinyarwanda or english",
        ),
        ("cuda yes", "f.ini:1: key 'cuda': value 'yes' is not a boolean; allowed: true or false"),
        (
            "quantization fp16",
            "f.ini:1: key 'quantization': value 'fp16' is not one of the choices; allowed: none or int8",
        ),
        (
            "speech_pause_period nan",
            "f.ini:1: key 'speech_pause_period': value 'nan' is not a number; "
            "allowed: a number of seconds from 0.2 to 60.0",
        ),
        (
            "max_utterance_length 0.5",
            "f.ini:1: key 'max_utterance_length': value '0.5' is out of range; "
            "allowed: a number of seconds from 1.0 to 300.0",
        ),
        ("verbose_mode", "f.ini:1: key 'verbose_mode': value '' is not a boolean; allowed: true or false"),
        ("= 5", "f.ini:1: cannot read '= 5'; expected 'key value' or 'key = value'"),
        (
            "speech_pause 1.0",
            "f.ini:1: unknown key 'speech_pause': did you mean 'speech_pause_period'? known keys are "
            "language, verbose_mode, rw_model_path, en_model_path, audio_storage_dir, audio_storage_max_mb, cuda, quantization, sample_rate, "
            "speech_pause_period, max_utterance_length, health_check_period, publish_unrecognized, "
            "max_message_length, confidence, heartbeat_msg_period, grammar, grammar_threshold, pocketsphinx_keywords, model, min_utterance_length, vad_threshold, max_backlog, recognition_timeout, speculative_recognition, speculation_gap, early_pause, complete_answers, partial_period, text_style, turn_end_model, turn_end_text, end_of_speech",
        ),
        (
            "samplerate 16000",
            "f.ini:1: unknown key 'samplerate': did you mean 'sample_rate'? known keys are "
            "language, verbose_mode, rw_model_path, en_model_path, audio_storage_dir, audio_storage_max_mb, cuda, quantization, sample_rate, "
            "speech_pause_period, max_utterance_length, health_check_period, publish_unrecognized, "
            "max_message_length, confidence, heartbeat_msg_period, grammar, grammar_threshold, pocketsphinx_keywords, model, min_utterance_length, vad_threshold, max_backlog, recognition_timeout, speculative_recognition, speculation_gap, early_pause, complete_answers, partial_period, text_style, turn_end_model, turn_end_text, end_of_speech",
        ),
    ],
)
def test_a_bad_file_gets_one_error_naming_file_line_key_value_and_what_is_allowed(
    text: str, message: str
) -> None:
    with pytest.raises(ConfigError) as error:
        parse_config(text, "f.ini")
    assert str(error.value) == message


def test_a_missing_file_is_named() -> None:
    with pytest.raises(ConfigError) as error:
        load_config("/nonexistent/speech.ini")
    assert (
        str(error.value)
        == "/nonexistent/speech.ini: cannot read the configuration file: No such file or directory"
    )


def test_typed_overrides_are_checked_like_file_values() -> None:
    base = SpeechEventConfig()
    assert apply_overrides(
        base, {"speechPausePeriod": 1, "publish_unrecognized": True}, "s"
    ) == SpeechEventConfig(speech_pause_period=1.0, publish_unrecognized=True)
    with pytest.raises(ConfigError) as error:
        apply_overrides(base, {"sample_rate": 16000.5}, "s.toml: [config]")
    assert str(error.value) == (
        "s.toml: [config]: key 'sample_rate': value 16000.5 is not an integer; "
        "allowed: an integer number of Hz from 8000 to 192000"
    )
    with pytest.raises(ConfigError) as error:
        apply_overrides(base, {"health_check_period": True}, "s")
    assert str(error.value) == (
        "s: key 'health_check_period': value True is not a number; "
        "allowed: a number of seconds from 0.1 to 3600.0"
    )


@given(
    pause=st.floats(0.52, 60.0, allow_nan=False),  # longer than a block at 8 kHz
    rate=st.integers(8000, 192000),
    verbose=st.booleans(),
    language=st.sampled_from(["kinyarwanda", "english"]),
)
def test_any_allowed_value_written_to_a_file_reads_back_the_same(
    pause: float, rate: int, verbose: bool, language: str
) -> None:
    text = f"speech_pause_period {pause!r}\nsample_rate {rate}\nverbose_mode {str(verbose).lower()}\nlanguage {language}\n"
    config = parse_config(text)
    assert (config.speech_pause_period, config.sample_rate, config.verbose_mode, config.language) == (
        pause,
        rate,
        verbose,
        language,
    )


def test_the_shipped_node_configuration_is_the_embedded_defaults() -> None:
    assert load_config(ROOT / "config" / "speech_event_configuration.ini") == SpeechEventConfig()


def test_a_bad_configuration_stops_the_program_with_status_2_before_anything_starts(tmp_path: Path) -> None:
    bad = tmp_path / "bad.ini"
    bad.write_text("language english\nsampleRate 48k\n")
    result = subprocess.run(
        [sys.executable, "-m", "harness", "demo", "-c", str(bad)], cwd=ROOT, capture_output=True, text=True
    )
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr == (
        f"error: {bad}:2: key 'sample_rate': value '48k' is not an integer; "
        "allowed: an integer number of Hz from 8000 to 192000\n"
    )


@given(
    pause=st.floats(0.2, 60.0),
    storage=st.text(alphabet="abc/_-.", max_size=20),
    unrecognized=st.booleans(),
    language=st.sampled_from(["kinyarwanda", "english"]),
)
def test_a_formatted_configuration_reads_back_the_same(
    pause: float, storage: str, unrecognized: bool, language: str
) -> None:
    config = SpeechEventConfig(
        speech_pause_period=pause,
        audio_storage_dir=storage,
        publish_unrecognized=unrecognized,
        language=language,
    )
    assert parse_config(format_config(config)) == config


def test_the_deployment_node_refuses_a_bad_configuration_with_status_2_before_touching_ros(
    tmp_path: Path,
) -> None:
    bad = tmp_path / "robot.ini"
    bad.write_text("verboseMode maybe\n")
    result = run_application("-c", str(bad), "--recognizer", "fake")
    assert result.returncode == 2
    assert (
        result.stderr
        == f"error: {bad}:1: key 'verbose_mode': value 'maybe' is not a boolean; allowed: true or false\n"
    )


ROBOT_V1_1 = ROOT / "config" / "robot_release_v1.1.ini"


def test_the_configuration_file_of_the_robots_release_loads_unchanged() -> None:
    # Exactly the robot's lines (reference.md, "The robot's current release (v1.1)").
    assert ROBOT_V1_1.read_text() == (
        "language\tenglish\nmodel\tconformer-transducer\nverboseMode\ttrue\ncuda\tfalse\n"
        "confidence\t0.0\nvadThreshold\t0.0\nsampleRate\t48000\ninterUtteranceLen\t1.5\n"
        "minUtteranceLen\t1.0\nmaxUtteranceLen\t15.0\nheartbeatMsgPeriod\t10\n"
    )
    assert load_config(ROBOT_V1_1) == SpeechEventConfig(
        language="english",
        model="conformer-transducer",
        verbose_mode=True,
        cuda=False,
        confidence=0.0,
        vad_threshold=0.0,
        sample_rate=48000,
        speech_pause_period=1.5,
        min_utterance_length=1.0,
        max_utterance_length=15.0,
        heartbeat_msg_period=10.0,
    )


@pytest.mark.parametrize(
    ("line", "message"),
    [
        (
            "model\ttransformer",
            "key 'model': value 'transformer' is not one of the choices; "
            "allowed: conformer-transducer or parakeet or whisper",
        ),
        (
            "vadThreshold 1.5",
            "key 'vad_threshold': value '1.5' is out of range; allowed: a speech probability from 0 to 1; 0: no check",
        ),
        (
            "minUtteranceLen -1",
            "key 'min_utterance_length': value '-1' is out of range; allowed: a number of seconds from 0.0 to 300.0",
        ),
    ],
)
def test_the_robots_new_keys_are_checked(line: str, message: str) -> None:
    with pytest.raises(ConfigError) as error:
        parse_config(line, "robot.ini")
    assert str(error.value) == f"robot.ini:1: {message}"


@pytest.mark.parametrize(
    ("family", "message"),
    [
        (
            "whisper",
            "language english with model whisper needs en_model_path: the directory of an exported whisper "
            "model (speech-event export-whisper CHECKPOINT DIR writes one)",
        ),
        (
            "parakeet",
            "language english with model parakeet needs en_model_path: the directory of an exported parakeet "
            "model (speech-event export-nemo MODEL.nemo DIR writes one)",
        ),
    ],
)
def test_a_model_family_without_its_model_directory_stops_the_node_with_status_2(
    tmp_path: Path, family: str, message: str
) -> None:
    robot = tmp_path / "robot.ini"
    robot.write_text(ROBOT_V1_1.read_text().replace("conformer-transducer", family))
    result = run_application("-c", str(robot))
    assert result.returncode == 2
    assert result.stderr == f"error: {message}\n"


def test_vad_threshold_without_the_silero_model_stops_the_node_saying_how_to_install_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    import importlib.util

    from speech_event.application import build_screen

    monkeypatch.setattr(importlib.util, "find_spec", lambda name: None)
    with pytest.raises(ConfigError) as error:
        build_screen(SpeechEventConfig(vad_threshold=0.5))
    assert str(error.value) == (
        "vad_threshold needs Silero VAD's ONNX model, shipped in the silero-vad wheel: "
        "pip install --no-deps silero-vad (its torch dependency is not needed)"
    )


def test_end_of_speech_left_unset_is_on_where_its_blocks_allow_and_decides_only_with_a_grammar() -> None:
    unset = parse_config("end_of_speech\nspeculation_gap\n")
    assert unset == SpeechEventConfig() and unset.end_of_speech is None and unset.speculation_gap is None
    assert end_of_speech_seconds(unset) == GRAMMAR_END_OF_SPEECH == 0.3
    assert not end_of_speech_chosen(unset)
    # A block at 8 kHz is 0.51 s: the gaps between blocks would be heard as ends.
    assert end_of_speech_seconds(parse_config("sample_rate 8000")) == 0.0
    assert end_of_speech_seconds(parse_config("sample_rate 16000")) == 0.3
    assert end_of_speech_seconds(parse_config("speech_pause_period 0.3")) == 0.0
    assert not ends_at_end_of_speech(parse_config("speculative_recognition false"))
    assert not ends_at_end_of_speech(parse_config("early_pause 0.5"))
    written = parse_config("end_of_speech 0.4")
    assert end_of_speech_seconds(written) == 0.4 and end_of_speech_chosen(written)
    off = parse_config("end_of_speech 0")
    assert end_of_speech_seconds(off) == 0.0 and not ends_at_end_of_speech(off)


def test_speculation_gap_left_unset_is_short_while_the_end_of_speech_decides() -> None:
    unset = SpeechEventConfig()
    assert speculation_gap_seconds(unset, deciding=True) == DECIDING_SPECULATION_GAP == 0.1
    assert speculation_gap_seconds(unset, deciding=False) == SPECULATION_GAP == 0.3
    assert speculation_gap_seconds(SpeechEventConfig(end_of_speech=0.0), deciding=True) == 0.3
    assert speculation_gap_seconds(SpeechEventConfig(early_pause=0.5), deciding=True) == 0.3
    assert speculation_gap_seconds(SpeechEventConfig(speculative_recognition=False), deciding=True) == 0.3
    assert speculation_gap_seconds(SpeechEventConfig(speculation_gap=0.2), deciding=True) == 0.2
    assert speculation_gap_seconds(SpeechEventConfig(speculation_gap=0.2), deciding=False) == 0.2


@pytest.mark.parametrize(
    ("line", "message"),
    [
        (
            "end_of_speech -1",
            "key 'end_of_speech': value '-1' is out of range; allowed: a number of seconds from 0 (off) to "
            "60, or nothing for 0.3 in grammar mode (Whisper, NeMo) and off elsewhere",
        ),
        (
            "speculation_gap 0.01",
            "key 'speculation_gap': value '0.01' is out of range; allowed: a number of seconds from 0.05 to "
            "60, or nothing for 0.1 where the turn ends at the end of speech and 0.3 elsewhere",
        ),
        (
            "end_of_speech 0.05",
            "end_of_speech 0.05 s is not longer than one 4096-sample block at sample_rate 48000 Hz (0.085 s): "
            "the gaps between blocks would be heard as the end of speech; 0 turns it off",
        ),
    ],
)
def test_end_of_speech_and_speculation_gap_values_name_what_is_allowed(line: str, message: str) -> None:
    with pytest.raises(ConfigError) as error:
        parse_config(line, "node.ini")
    assert message in str(error.value)
