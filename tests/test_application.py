"""Starting up as a user does: from any folder, with odd configuration files, with or without ROS."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from fixtures.application import run_application
from fixtures.paths import ROOT
from speech_event.config import SpeechEventConfig, load_config, parse_config
from speech_event.errors import ConfigError


def _elsewhere(tmp_path: Path, *command: str) -> "subprocess.CompletedProcess[str]":
    """Run ``command`` from a folder that is not the checkout, with the checkout off the path."""
    environment = {key: value for key, value in os.environ.items() if key != "PYTHONPATH"}
    return subprocess.run(
        list(command), cwd=tmp_path, env=environment, capture_output=True, text=True, timeout=300
    )


def test_the_demo_runs_from_any_folder(tmp_path: Path) -> None:
    result = _elsewhere(
        tmp_path, sys.executable, "-m", "harness", "demo", "--voice", "tones", "--recognizer", "fake"
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[-1] == "/speechEvent/text at t=2.524 s: 'go to the kitchen'"


def test_the_demo_finds_its_command_grammar_from_any_folder(tmp_path: Path) -> None:
    result = _elsewhere(tmp_path, sys.executable, "-m", "harness", "demo", "go to the kitchen")
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines()[-1].endswith(" s: 'go to the kitchen'")


def test_the_node_without_ros_says_so_in_one_line_and_exits_2(tmp_path: Path) -> None:
    """The console script, no -c: the embedded defaults; then ROS 1 is missing (the py env has no rospy)."""
    script = Path(sys.executable).parent / "speech-event"  # installed with the package, as pip does
    result = _elsewhere(tmp_path, str(script), "--recognizer", "fake")
    assert result.returncode == 2
    assert result.stdout == ""
    (line,) = result.stderr.splitlines()
    assert line.startswith(
        "error: the node needs ROS 1 (rospy, actionlib, diagnostic_msgs), which this Python cannot import ("
    )
    assert line.endswith("); see README.md, 'On ROS and on the robot'")


def test_a_byte_order_mark_is_accepted(tmp_path: Path) -> None:
    path = tmp_path / "windows.ini"
    path.write_bytes(b"\xef\xbb\xbflanguage kinyarwanda\r\nsampleRate 16000\r\n")
    assert load_config(path) == SpeechEventConfig(language="kinyarwanda", sample_rate=16000)


def test_a_file_over_1_mb_is_refused_in_one_line(tmp_path: Path) -> None:
    path = tmp_path / "huge.ini"
    path.write_text("# " + "x" * 2**20 + "\n")
    with pytest.raises(ConfigError) as error:
        load_config(path)
    assert (
        str(error.value)
        == f"{path}: the configuration file is over 1 MB; a configuration is a few lines of 'key value'"
    )


def test_dev_zero_is_refused_without_filling_memory() -> None:
    with pytest.raises(ConfigError) as error:
        load_config("/dev/zero")
    assert str(error.value).startswith("/dev/zero: the configuration file is over 1 MB")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (
            "speech_pause_period 0.1",
            "f.ini:1: key 'speech_pause_period': value '0.1' is out of range; allowed: a number of seconds from 0.2 to 60.0",
        ),
        (
            "sample_rate 8000\nspeech_pause_period 0.5",
            "f.ini: speech_pause_period 0.5 s is not longer than one 4096-sample block at sample_rate 8000 Hz "
            "(0.512 s): speech would be cut between blocks",
        ),
        (
            "max_message_length 0.1\nsample_rate 16000",
            "f.ini: max_message_length 0.1 s is shorter than one 4096-sample block at sample_rate 16000 Hz "
            "(0.256 s): every block would be rejected",
        ),
        (
            "min_utterance_length 12\nmax_utterance_length 10",
            "f.ini: min_utterance_length 12.0 s is longer than max_utterance_length 10.0 s: no utterance would "
            "ever be transcribed",
        ),
        (
            "end_of_speech 0.05",
            "f.ini: end_of_speech 0.05 s is not longer than one 4096-sample block at sample_rate 48000 Hz "
            "(0.085 s): the gaps between blocks would be heard as the end of speech; 0 turns it off",
        ),
        (
            "end_of_speech 2",
            "f.ini: end_of_speech 2.0 s must be less than speech_pause_period (1.5 s): 0 turns it off",
        ),
    ],
)
def test_values_that_do_not_work_together_are_refused(text: str, message: str) -> None:
    with pytest.raises(ConfigError) as error:
        parse_config(text, "f.ini")
    assert str(error.value) == message


@pytest.mark.parametrize("script", sorted(path.name for path in (ROOT / "scripts").glob("*.py")))
def test_a_script_run_by_a_python_without_the_project_says_so_in_one_line(
    script: str, tmp_path: Path
) -> None:
    # As a new user ran scripts/speech_event_driver.py with /usr/bin/python3 (issue 17, item 4):
    # -I -S is a Python that sees neither the checkout nor any site-packages.
    result = _elsewhere(tmp_path, sys.executable, "-I", "-S", str(ROOT / "scripts" / script))
    assert result.returncode == 2
    assert result.stdout == ""
    missing = (
        "harness" if script not in ("speech_event_application.py", "speech_event_gui.py") else "speech_event"
    )
    assert result.stderr == (
        f"error: {sys.executable} cannot import {missing}: see README.md, 'On ROS and on the robot'\n"
    )


def test_python_m_speech_event_is_the_node_as_its_script_runs_it(tmp_path: Path) -> None:
    # What the ROS replay starts: it needs no scripts/ folder, which an installed package lacks.
    config = tmp_path / "bad.ini"
    config.write_text("speech_pause_period fast\n")
    module = subprocess.run(
        [sys.executable, "-m", "speech_event", "-c", str(config)],
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
    )
    script = run_application("-c", str(config))
    assert (module.returncode, module.stdout, module.stderr) == (
        script.returncode,
        script.stdout,
        script.stderr,
    )
    assert module.returncode == 2 and module.stderr.startswith("error: ")
