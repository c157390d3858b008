import dataclasses
import subprocess
import sys
from pathlib import Path
from typing import Any, Dict, List

import pytest

from fixtures.paths import ROOT
from fixtures.processes import children
from fixtures.scenario_files import SCENARIOS
from harness.cli import COMMANDS, base_config, build_parser, demo_engine
from harness.memory_runner import run_in_memory
from harness.outcome import REAL_TIME, SIM_TIME, Published
from harness.report import passed, report
from harness.scenario import ScenarioError, load_scenario, parse_scenario
from speech_event import SOUND_DETECTION_DOWN
from speech_event.config import SpeechEventConfig


def test_there_are_scenarios_for_every_behaviour_the_issue_names() -> None:
    names = {path.stem for path in SCENARIOS}
    kinds = ("empty", "nan", "inf", "out_of_range", "multichannel", "oversized", "wrong_type")
    assert {f"malformed_{kind}" for kind in kinds} <= names
    assert {
        "single_utterance",
        "several_utterances",
        "long_utterance_split",
        "noise_only",
        "outage_shutdown",
        "outage_crash",
        "outage_right_after_speech",
        "outage_then_recovery",
    } <= names


def test_a_replay_is_deterministic_to_the_message_and_the_time() -> None:
    scenario = load_scenario(ROOT / "scenarios" / "outage_crash.toml", SpeechEventConfig())
    first = run_in_memory(scenario).published
    assert first == run_in_memory(scenario).published
    block = 4096 / 48000
    # "hello" fills 5 blocks; the 1.5 s pause closes it; checks at 2, 4, 6 s find soundDetection down.
    assert [message.time for message in first[:4]] == pytest.approx([5 * block + 1.5, 2.0, 4.0, 6.0])


def test_a_run_leaves_no_engine_process_behind() -> None:
    """pocketsphinx runs in a process of its own: each in-memory run closes the engines it built,
    or a test session would hold one per run until the garbage collector found it."""
    before = children()
    scenario = load_scenario(ROOT / "scenarios" / "tts_command.toml", SpeechEventConfig())
    assert passed(scenario, run_in_memory(scenario))
    assert children() == before


MINIMAL: Dict[str, Any] = {"name": "n", "steps": [{"say": "hi"}], "expect": {"published": ["hi"]}}


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            {"nmae": "x"},
            "s.toml: unknown key 'nmae'; allowed keys: name, voice, recognizer, background_noise_db, seed, config, steps, expect",
        ),
        ({"name": None}, "s.toml: 'name' is required"),
        (
            {"steps": [{"say": "hi", "silence": 1}]},
            "s.toml: steps[0]: a step needs exactly one of say, play, silence, noise, malformed, outage, enable, language, grammar, listen; it has say, silence",
        ),
        (
            {"steps": [{"say": "hi", "noise": "pink"}]},
            "s.toml: steps[0]: 'noise' and 'snr_db' go together: give both or neither",
        ),
        (
            {"steps": [{"say": "hi", "noise": "pink", "snr_db": 200}]},
            "s.toml: steps[0]: 'snr_db' = 200.0 must be a number of dB from -40 to 100",
        ),
        (
            {"steps": [{"play": "missing.wav"}]},
            "s.toml: play = 'missing.wav': there is no file missing.wav; allowed: a sound file next to the scenario",
        ),
        (
            {"steps": [{"noise": 2, "kind": "purple"}]},
            "s.toml: kind = 'purple': there is no file purple; allowed: a sound file next to the scenario or one of white, pink, brown, babble",
        ),
        (
            {"steps": [{"play": "x.wav", "level_db": 3}]},
            "s.toml: steps[0]: unknown key 'level_db'; allowed keys: play, gain_db, noise, snr_db",
        ),
        (
            {"steps": [{"silence": -1}]},
            "s.toml: steps[0]: 'silence' = -1.0 must be a number of seconds above 0 and at most 3600",
        ),
        (
            {"steps": [{"malformed": "garbled"}]},
            "s.toml: steps[0]: 'malformed' = 'garbled' is not allowed; allowed: empty, nan, inf, out_of_range, multichannel, oversized, wrong_type",
        ),
        (
            {"steps": [{"outage": 2, "kind": "explode"}]},
            "s.toml: steps[0]: 'kind' = 'explode' is not allowed; allowed: shutdown, crash",
        ),
        (
            {"steps": [{"say": "Hello!"}]},
            "s.toml: steps[0]: the tones voice cannot speak '!', 'H'; it speaks only [a-z' ]",
        ),
        ({"steps": [{"say": 5}]}, "s.toml: steps[0]: 'say' = 5 must be of type str"),
        ({"voice": "robot"}, "s.toml: 'voice' = 'robot' is not allowed; allowed: tones, tts, slt, kal, ked"),
        (
            {"config": {"speech_pause": 1}},
            "s.toml: [config]: unknown key 'speech_pause': did you mean 'speech_pause_period'? known keys are language, verbose_mode, rw_model_path, en_model_path, audio_storage_dir, audio_storage_max_mb, cuda, quantization, sample_rate, speech_pause_period, max_utterance_length, health_check_period, publish_unrecognized, max_message_length, confidence, heartbeat_msg_period, grammar, grammar_threshold, pocketsphinx_keywords, model, min_utterance_length, vad_threshold, max_backlog, recognition_timeout, speculative_recognition, speculation_gap, early_pause, complete_answers, partial_period, text_style, turn_end_model, turn_end_text, end_of_speech",
        ),
        ({"expect": {"published": [1]}}, "s.toml: [expect]: 'published' must be a list of strings"),
    ],
)
def test_a_bad_scenario_is_refused_with_where_and_what_is_allowed(
    change: Dict[str, Any], message: str
) -> None:
    document = {**MINIMAL, **change}
    document = {key: value for key, value in document.items() if value is not None}
    with pytest.raises(ScenarioError) as error:
        parse_scenario(document, "s.toml", SpeechEventConfig())
    assert str(error.value) == message


@pytest.mark.parametrize("spelling", ["grammar", "pocketsphinx_grammar"])
def test_a_grammar_in_config_is_read_next_to_the_scenario_under_its_old_name_too(
    spelling: str, tmp_path: Path
) -> None:
    (tmp_path / "commands.txt").write_text("go left\nstop\n")
    path = tmp_path / "s.toml"
    path.write_text(
        f'name = "n"\n[config]\n{spelling} = "commands.txt"\n'
        '[[steps]]\nsay = "go right"\n[[steps]]\nsilence = 2.0\n[[steps]]\nsay = "go left"\n'
        '[expect]\npublished = ["go left"]\n'
    )
    scenario = load_scenario(path, SpeechEventConfig())
    outcome = run_in_memory(scenario)
    assert [message.text for message in outcome.published] == ["go left"]  # "go right": no phrase
    assert passed(scenario, outcome)


@pytest.mark.parametrize(
    ("spelling", "key"),
    [
        ("rwModelPath", "rw_model_path"),
        ("enModelPath", "en_model_path"),
        ("audioStorageDir", "audio_storage_dir"),
        ("pocketsphinxKeywords", "pocketsphinx_keywords"),
        ("pocketsphinx_grammar", "grammar"),
    ],
)
def test_every_spelling_of_a_path_key_is_taken_from_the_scenarios_folder(spelling: str, key: str) -> None:
    scenario = parse_scenario({**MINIMAL, "config": {spelling: "data/x"}}, "/s/t.toml", SpeechEventConfig())
    assert getattr(scenario.config, key) == "/s/data/x"


def _harness(*arguments: str) -> "subprocess.CompletedProcess[str]":
    return subprocess.run(
        [sys.executable, "-m", "harness", *arguments], cwd=ROOT, capture_output=True, text=True
    )


def test_the_cli_prints_a_line_per_scenario_and_exits_0_when_all_pass() -> None:
    result = _harness(
        "run", "--transport", "memory", "scenarios/single_utterance.toml", "scenarios/noise_only.toml"
    )
    assert result.returncode == 0
    assert result.stdout == (
        "PASS  one command  (scenarios/single_utterance.toml, 1 messages)\n"
        "PASS  noise alone publishes nothing  (scenarios/noise_only.toml, 0 messages)\n"
        "2 passed, 0 failed\n"
    )


def test_the_cli_shows_a_diff_and_exits_1_when_a_scenario_fails(tmp_path: Path) -> None:
    wrong = tmp_path / "wrong.toml"
    wrong.write_text('name = "wrong"\n[[steps]]\nsay = "go left"\n[expect]\npublished = ["go right"]\n')
    result = _harness("run", str(wrong))
    assert result.returncode == 1
    assert result.stdout == (
        f"FAIL  wrong  ({wrong})\n"
        "      --- expected\n"
        "      +++ published\n"
        "      @@ -1 +1 @@\n"
        "      -go right\n"
        "      +go left\n"
        "      published, with scenario times:\n"
        "        t=   2.012 s  'go left'\n"  # 6 blocks end at 0.512 s, then the 1.5 s pause
        "0 passed, 1 failed\n"
    )


def test_a_scenario_that_cannot_be_loaded_is_named_and_the_others_still_run(tmp_path: Path) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text("name = \n")
    result = _harness("run", str(bad), "scenarios/single_utterance.toml")
    assert result.returncode == 1
    lines = result.stdout.splitlines()
    assert lines[0] == f"FAIL  bad  ({bad})"
    assert lines[1].startswith(f"      cannot run: {bad}: not valid TOML: ")
    assert lines[2:] == [
        "PASS  one command  (scenarios/single_utterance.toml, 1 messages)",
        "1 passed, 1 failed",
    ]


@pytest.mark.parametrize(
    ("hidden", "scenario", "says"),
    [
        # After the demo's install alone (no silero-vad), as a new user found (issue 17, item 4).
        (
            "silero_vad",
            "tts_vad_threshold",
            "vad_threshold needs Silero VAD's ONNX model, shipped in the silero-vad wheel: "
            "pip install --no-deps silero-vad (its torch dependency is not needed)",
        ),
        # After a plain 'pip install .' (no test extra), as replaying every scenario showed.
        (
            "onnx",
            "grammar_fixture_ctc",
            "the fixture models are built with onnx, which this Python lacks: pip install 'speech-event[test]'",
        ),
    ],
)
def test_a_scenario_whose_package_is_not_installed_says_what_to_install_and_the_others_run(
    hidden: str, scenario: str, says: str
) -> None:
    code = (
        f"import sys; sys.modules[{hidden!r}] = None; from harness.cli import main; "
        f"sys.exit(main(['run', 'scenarios/{scenario}.toml', 'scenarios/single_utterance.toml']))"
    )
    result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True)
    assert result.returncode == 1
    assert result.stdout.splitlines() == [
        f"FAIL  {scenario}  (scenarios/{scenario}.toml)",
        f"      cannot run: {says}",
        "PASS  one command  (scenarios/single_utterance.toml, 1 messages)",
        "1 passed, 1 failed",
    ]


def test_the_demo_turns_real_speech_into_text_on_embedded_defaults() -> None:
    """Whisper tiny.en int8 (the test extra's wheel) within the robot's commands: the engine that
    published one other word as a command on recordings of people, pocketsphinx 14 of 30 digits
    (docs/grammar.md#people)."""
    result = _harness("demo", "go to the kitchen")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[:2] == [
        "soundDetection says 'go to the kitchen' (tts voice, 48000 Hz, 4096-sample blocks)",
        "speechEvent transcribes with whisper-tiny.en (int8), "
        f"grammar {ROOT / 'harness' / 'data' / 'robot_commands.txt'}",
    ]
    assert len(lines) == 3
    assert lines[2].startswith("/speechEvent/text at t=")
    assert lines[2].endswith(" s: 'go to the kitchen'")


def test_the_demo_on_pocketsphinx_takes_the_robots_commands_too() -> None:
    result = _harness("demo", "--recognizer", "pocketsphinx", "go to the kitchen")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert lines[1] == (
        f"speechEvent transcribes with pocketsphinx, grammar {ROOT / 'harness' / 'data' / 'robot_commands.txt'}"
    )
    assert lines[2].endswith(" s: 'go to the kitchen'")


def test_the_demo_with_the_tones_voice_and_the_fake_recognizer() -> None:
    result = _harness("demo", "--voice", "tones", "--recognizer", "fake", "hello there")
    assert result.stdout.splitlines()[1:] == [
        "speechEvent transcribes with fake",
        "/speechEvent/text at t=2.268 s: 'hello there'",  # 9 blocks, then the 1.5 s pause
    ]


@pytest.mark.parametrize("option", [["--node-command", "other_node {config}"], ["--config-dir", "/tmp"]])
def test_ros_only_options_are_refused_in_memory(option: List[str]) -> None:
    result = _harness("run", *option, "scenarios/single_utterance.toml")
    assert result.returncode == 2
    assert result.stdout == ""
    assert result.stderr == (
        "error: --node-command and --config-dir need --transport ros: in memory the node under test is ours\n"
    )


def test_a_failure_report_carries_the_hint_it_is_given(tmp_path: Path) -> None:
    scenario = parse_scenario({**MINIMAL, "expect": {"published": ["bye"]}}, "s.toml", SpeechEventConfig())
    text = report(scenario, run_in_memory(scenario), "sim-time replay drives /clock")
    assert text.splitlines()[-1] == "      note: sim-time replay drives /clock"
    assert report(scenario, run_in_memory(scenario)).splitlines()[-1].startswith("        t=")


# -- [expect] partials and transcripts ------------------------------------------------------------


def _expecting(partials: List[Any], transcripts: List[Any]) -> Any:
    document = {**MINIMAL, "steps": [{"say": "go left"}]}
    document["expect"] = {"published": ["go left"], "partials": partials, "transcripts": transcripts}
    return parse_scenario(document, "s.toml", SpeechEventConfig(sample_rate=16000))


@pytest.mark.parametrize(
    "partials, transcripts, message",
    [
        (
            ["go"],
            [],
            "s.toml: [expect]: 'partials' must be a list of tables such as { at = 0.75, text = \"go to\" }",
        ),
        ([{"at": 0.5}], [], "s.toml: [expect]: partials[0]: 'text' is required"),
        (
            [{"at": -1, "text": "go"}],
            [],
            "s.toml: [expect]: partials[0]: 'at' = -1.0 must be a number of seconds 0 or more and at most 3600",
        ),
        ([], [{"text": "go"}], "s.toml: [expect]: transcripts[0]: 'final' is required"),
        (
            [],
            [{"text": "go", "final": "yes"}],
            "s.toml: [expect]: transcripts[0]: 'final' = 'yes' must be of type bool",
        ),
        (
            [],
            [{"text": "go", "final": True, "stamp": 1.0}],
            "s.toml: [expect]: transcripts[0]: unknown key 'stamp'; allowed keys: text, final, confidence, language, engine, first_block, last_block",
        ),
    ],
)
def test_a_bad_partial_or_transcript_expectation_is_refused_with_where_and_what_is_allowed(
    partials: List[Any], transcripts: List[Any], message: str
) -> None:
    with pytest.raises(ScenarioError) as error:
        _expecting(partials, transcripts)
    assert str(error.value) == message


def test_partials_are_checked_with_their_times_in_memory_by_their_texts_in_sim_time_not_in_real_time() -> (
    None
):
    # "go left" in the tones voice at 16 kHz: blocks from 0.256 s, its last at 0.512 s.
    right = _expecting(
        [{"at": 0.756, "text": "go left"}],
        [{"text": "go left", "final": False, "first_block": 0.256}, {"text": "go left", "final": True}],
    )
    late = _expecting(
        [{"at": 0.9, "text": "go left"}],
        [{"text": "go left", "final": False, "first_block": 0.3}, {"text": "go left", "final": True}],
    )
    wrong = _expecting([{"at": 0.756, "text": "go"}], [])
    outcome = run_in_memory(right)
    assert [(round(p.time, 3), p.text) for p in outcome.partials] == [(0.756, "go left")]
    assert passed(right, outcome)
    assert not passed(late, outcome)
    assert "      -t=0.900 s  'go left'\n      +t=0.756 s  'go left'" in report(late, outcome)
    assert (
        "      -text='go left', final=False, first_block=0.300\n      +text='go left', final=False, first_block=0.256"
        in report(late, outcome)
    )
    sim_time = dataclasses.replace(outcome, clock=SIM_TIME)
    assert passed(late, sim_time)
    assert not passed(wrong, sim_time)
    assert passed(wrong, dataclasses.replace(outcome, clock=REAL_TIME))


def test_in_real_time_an_error_may_come_before_a_text_still_being_recognized_but_no_text_may_change() -> None:
    scenario = load_scenario(str(ROOT / "scenarios" / "outage_right_after_speech.toml"), SpeechEventConfig())
    outcome = run_in_memory(scenario)
    stop, error = outcome.published
    assert (stop.text, error.text) == ("stop", SOUND_DETECTION_DOWN)
    # "stop" recognized after the health check, as on a busy machine on the wall clock
    late = dataclasses.replace(outcome, published=[error, Published(error.time + 0.1, "stop")])
    assert passed(scenario, dataclasses.replace(late, clock=REAL_TIME))
    assert not passed(scenario, dataclasses.replace(late, clock=SIM_TIME))
    wrong = dataclasses.replace(
        outcome, published=[error, Published(error.time + 0.1, "go")], clock=REAL_TIME
    )
    assert not passed(scenario, wrong)
    assert "--- expected published texts\n      +++ published texts\n" in report(scenario, wrong)
    twice = dataclasses.replace(wrong, published=[stop, error, error])
    assert not passed(scenario, twice)


@pytest.mark.parametrize(
    ("options", "lines", "engine", "quantization", "grammar"),
    [
        ([], [], "whisper-tiny.en", "int8", str(COMMANDS)),
        (["--recognizer", "pocketsphinx"], [], "pocketsphinx", "none", str(COMMANDS)),
        (["--grammar", ""], [], "whisper-tiny.en", "int8", ""),
        (["--recognizer", "fake"], [], "fake", "none", ""),
        ([], ["en_model_path /models/en"], "auto", "none", ""),  # the user's model, as the file says
        ([], ["model whisper"], "auto", "none", ""),
        ([], ["quantization none"], "whisper-tiny.en", "none", str(COMMANDS)),
    ],
)
def test_the_demo_runs_whisper_tiny_en_int8_with_the_commands_unless_told_otherwise(
    tmp_path: Path, options: List[str], lines: List[str], engine: str, quantization: str, grammar: str
) -> None:
    if lines:
        (tmp_path / "demo.ini").write_text("\n".join(lines) + "\n")
        options = [*options, "-c", str(tmp_path / "demo.ini")]
    arguments = build_parser().parse_args(["demo", *options])
    chosen = demo_engine(arguments, base_config(arguments.config))
    assert (chosen.recognizer, chosen.config.quantization, chosen.config.grammar) == (
        engine,
        quantization,
        grammar,
    )
    assert chosen.notice == ""
