"""python -m harness run --transport ros: every scenario on a real roscore, as in memory."""

import json
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Dict, Set

import pytest
import rosgraph

from fixtures.paths import ROOT
from fixtures.ros import ros_environment
from fixtures.scenario_files import SCENARIOS, TONES_SCENARIOS, shard
from harness.processes import descendants
from harness.ros.runner import route_address
from speech_event import TEXT_TOPIC

# Real time replays every scenario on the wall clock (about 500 s in all): in parts, side by side.
REAL_TIME_SHARDS = 8
SIM_TIME_SHARDS = 6


def _harness(environment: Dict[str, str], *arguments: str) -> "subprocess.CompletedProcess[str]":
    return subprocess.run(
        [sys.executable, "-m", "harness", "run", "--transport", "ros", *arguments],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        text=True,
        timeout=1200,
    )


def _own_roscore_environment(tmp_path: Path) -> Dict[str, str]:
    environment = ros_environment(0, tmp_path)
    del environment["ROS_MASTER_URI"]  # the harness starts its own roscore on a free port
    return environment


def _against_node(
    tmp_path: Path, source: str, placeholders: str, *arguments: str
) -> "subprocess.CompletedProcess[str]":
    """The harness replaying against the node that the Python ``source`` runs, given the runner's
    ``placeholders`` ({config}, {recognizer}), with ``arguments`` after --node-command."""
    node = tmp_path / "node_under_test.py"
    node.write_text(source)
    command = f"{sys.executable} {node} {placeholders}"
    return _harness(_own_roscore_environment(tmp_path), "--node-command", command, *arguments)


@pytest.mark.parametrize("part", range(SIM_TIME_SHARDS))
def test_every_scenario_passes_on_ros_with_the_in_memory_expectations(tmp_path: Path, part: int) -> None:
    scenarios = shard(SCENARIOS, part, SIM_TIME_SHARDS)
    result = _harness(
        _own_roscore_environment(tmp_path), *[str(path.relative_to(ROOT)) for path in scenarios]
    )
    lines = result.stdout.splitlines()
    assert lines[-1] == f"{len(scenarios)} passed, 0 failed", result.stdout + result.stderr
    assert [line.split("  ")[0] for line in lines[:-1]] == ["PASS"] * len(scenarios)
    assert result.returncode == 0


@pytest.mark.parametrize("part", range(SIM_TIME_SHARDS))
@pytest.mark.parametrize("model", ["fixture-parakeet", "fixture-whisper"])
def test_every_tones_scenario_passes_on_ros_with_the_other_families_fixture_models(
    tmp_path: Path, model: str, part: int
) -> None:
    """The TDT tones model and the Whisper tones model loaded by the node's process, as in memory."""
    copies = []
    scenarios = shard(TONES_SCENARIOS, part, SIM_TIME_SHARDS)
    for path in scenarios:
        copy = tmp_path / path.name
        copy.write_text(f'recognizer = "{model}"\n{path.read_text()}')
        copies.append(str(copy))
    result = _harness(_own_roscore_environment(tmp_path), *copies)
    lines = result.stdout.splitlines()
    assert lines[-1] == f"{len(scenarios)} passed, 0 failed", result.stdout + result.stderr
    assert result.returncode == 0


def test_a_failing_scenario_on_ros_shows_its_diff_and_exits_1(tmp_path: Path) -> None:
    wrong = tmp_path / "wrong.toml"
    wrong.write_text('name = "wrong"\n[[steps]]\nsay = "go left"\n[expect]\npublished = ["go right"]\n')
    result = _harness(_own_roscore_environment(tmp_path), str(wrong))
    assert result.returncode == 1
    assert "      -go right\n      +go left\n" in result.stdout
    assert "        t=   2.012 s  'go left'\n" in result.stdout  # as in memory: sim time is exact


def test_a_text_that_never_comes_fails_the_scenario_saying_how_long_the_replay_waited(tmp_path: Path) -> None:
    """The replay waits for an expected text until it comes or the deadline passes (a fixed second
    failed CI on a busy machine); here the node under test never publishes it."""
    silent = (
        "import sys\n"
        "from speech_event.pipeline.publication import Publication\n"
        "Publication.conclude = lambda self, job, outcome: None  # recognizes, publishes nothing\n"
        "from speech_event.application import main\n"
        "sys.exit(main(['-c', sys.argv[1], '--recognizer', 'fake']))\n"
    )
    began = time.monotonic()
    result = _against_node(
        tmp_path,
        silent,
        "{config}",
        "--text-deadline",
        "3",
        "scenarios/single_utterance.toml",
    )
    assert result.returncode == 1
    lines = result.stdout.splitlines()
    first = lines.index(
        "      gave up: at t=2.524 s, waited 3.0 s for 1 text(s) that the node published by then in memory; "
        "the node's last lines:"
    )
    assert lines[first + 1] == "        (no output)", (
        result.stdout
    )  # what the node said (not verbose: nothing)
    # the scenario is failed already: its later waits are short, and say so once
    later = [line.strip() for line in lines[first + 1 :] if line.strip().startswith("gave up:")]
    assert later and all(
        line.endswith(", waited 1.0 s for 1 text(s) that the node published by then in memory")
        for line in later
    ), result.stdout
    assert lines[-1] == "0 passed, 1 failed"
    assert time.monotonic() - began < 60  # the later waits of a scenario that missed one are short


def test_a_text_connection_made_late_loses_no_text(tmp_path: Path) -> None:
    """On a busy machine the replay's connection to the node's texts was made after the scenario
    began: the node published "still here" before it and the replay waited for it in vain. Here
    that connection is made 2 s late, every time: the replay waits for the node to accept it."""
    late_replay = tmp_path / "late_replay.py"
    late_replay.write_text(
        "import sys, time\n"
        "import rospy.impl.tcpros_pubsub as pubsub\n"
        "connect = pubsub.robust_connect_subscriber\n"
        "def late(*arguments):\n"
        f"    if arguments[-1] == {TEXT_TOPIC!r}:\n"
        "        time.sleep(2.0)\n"
        "    connect(*arguments)\n"
        "pubsub.robust_connect_subscriber = late\n"
        "from harness.cli import main\n"
        "sys.exit(main(sys.argv[1:]))\n"
    )
    environment = _own_roscore_environment(tmp_path)
    environment["PYTHONPATH"] = str(ROOT)
    result = subprocess.run(
        [
            sys.executable,
            str(late_replay),
            "run",
            "--transport",
            "ros",
            "--text-deadline",
            "10",
            "scenarios/single_utterance.toml",
        ],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert result.stdout.splitlines()[-1] == "1 passed, 0 failed", result.stdout + result.stderr


def test_a_node_slow_to_start_is_heard_from_before_the_scenario_plays(tmp_path: Path) -> None:
    """On a busy machine our node's start (its action server) took as long as 'hello': the replay
    played it meanwhile, the node's health checks counted from 0.43 s, and outage_crash's check
    at 2 s missed the crash (CI). Here the action server comes 2 s after the node listens, every
    time: the node's checks count from before it listens, and the replay waits for it to say so."""
    slow_node = (
        "import sys, time\n"
        "from speech_event.adapters.ros import RosTransport\n"
        "serve_action = RosTransport.serve_action\n"
        "def late(*arguments):\n"
        "    time.sleep(2.0)\n"
        "    serve_action(*arguments)\n"
        "RosTransport.serve_action = late\n"
        "from speech_event.application import main\n"
        "sys.exit(main(['-c', sys.argv[1], '--recognizer', sys.argv[2]]))\n"
    )
    result = _against_node(tmp_path, slow_node, "{config} {recognizer}", "scenarios/outage_crash.toml")
    assert result.stdout.splitlines()[-1] == "1 passed, 0 failed", result.stdout + result.stderr


def test_node_command_runs_the_scenarios_against_another_node(tmp_path: Path) -> None:
    marker = tmp_path / "ran"
    other_node = (
        "import sys\n"
        f"open({str(marker)!r}, 'w').write(sys.argv[1])\n"
        "from speech_event.application import main\n"
        "sys.exit(main(['-c', sys.argv[1], '--recognizer', 'fake']))\n"
    )
    result = _against_node(tmp_path, other_node, "{config}", "scenarios/single_utterance.toml")
    assert result.stdout.splitlines()[-1] == "1 passed, 0 failed", result.stdout + result.stderr
    assert marker.read_text().endswith("speech_event_configuration.ini")


@pytest.mark.parametrize("part", range(REAL_TIME_SHARDS))
def test_real_time_replay_passes_every_scenario_on_the_wall_clock(tmp_path: Path, part: int) -> None:
    scenarios = shard(SCENARIOS, part, REAL_TIME_SHARDS)
    result = _harness(
        _own_roscore_environment(tmp_path),
        "--real-time",
        *[str(path.relative_to(ROOT)) for path in scenarios],
    )
    assert result.stdout.splitlines()[-1] == f"{len(scenarios)} passed, 0 failed", (
        result.stdout + result.stderr
    )


def test_the_node_command_is_split_before_its_placeholders_are_filled(tmp_path: Path) -> None:
    arguments = tmp_path / "arguments.json"
    wrapper = tmp_path / "other node.py"  # a space in the path: still one word
    wrapper.write_text(
        "import json, sys\n"
        f"json.dump(sys.argv[1:], open({str(arguments)!r}, 'w'))\n"
        "from speech_event.application import main\n"
        "sys.exit(main(['-c', sys.argv[1], '--recognizer', sys.argv[3]]))\n"
    )
    result = _harness(
        _own_roscore_environment(tmp_path),
        "--node-command",
        f"{sys.executable} '{wrapper}' {{config}} '${{HOME}}' {{recognizer}}",
        "scenarios/single_utterance.toml",
    )
    assert result.stdout.splitlines()[-1] == "1 passed, 0 failed", result.stdout + result.stderr
    config, home, recognizer = json.loads(arguments.read_text())
    assert (config.endswith("speech_event_configuration.ini"), home, recognizer) == (True, "${HOME}", "fake")


def test_a_node_command_that_exits_at_once_is_reported_at_once_with_its_output(tmp_path: Path) -> None:
    started = time.monotonic()
    result = _harness(
        _own_roscore_environment(tmp_path),
        "--node-command",
        f"{sys.executable} -c \"import sys; print('no model here', file=sys.stderr); sys.exit(3)\"",
        "scenarios/single_utterance.toml",
    )
    assert time.monotonic() - started < 30  # not the 60 s start-up timeout
    assert result.returncode == 1
    assert result.stderr.splitlines()[-2:] == [
        "error: the replay could not go on: the node under test exited with status 3 before it subscribed "
        "to /soundDetection/signal; its last output:",
        "no model here",
    ]


def test_a_node_command_that_does_not_exist_is_one_clear_error(tmp_path: Path) -> None:
    result = _harness(
        _own_roscore_environment(tmp_path),
        "--node-command",
        "/no/such/node {config}",
        "scenarios/single_utterance.toml",
    )
    assert result.returncode == 1
    # one line of ours (rospy may log its own connection warnings before it), no traceback
    assert result.stderr.splitlines()[-1] == (
        "error: the replay could not go on: cannot start the node (/no/such/node): No such file or directory"
    )
    assert "Traceback" not in result.stderr


def test_a_given_ros_master_uri_is_used_instead_of_a_new_roscore(roscore: Dict[str, str]) -> None:
    master = rosgraph.Master("/replayTest", master_uri=roscore["ROS_MASTER_URI"])
    master.setParam("/use_sim_time", False)
    try:
        result = _harness(roscore, "scenarios/single_utterance.toml")
        assert result.stdout.splitlines()[-1] == "1 passed, 0 failed", result.stdout + result.stderr
        assert master.getParam("/use_sim_time") is True
    finally:  # the session's roscore: later tests' nodes run on the wall clock
        master.setParam("/use_sim_time", False)


@pytest.mark.parametrize(
    ("stop_signal", "status", "said"),
    [(signal.SIGINT, 130, "interrupted"), (signal.SIGTERM, 143, "terminated")],
)
def test_ctrl_c_or_sigterm_stops_every_process_the_replay_started(
    tmp_path: Path, stop_signal: int, status: int, said: str
) -> None:
    # Ten minutes on the wall clock: the signal always comes while it plays (a short sim-time
    # scenario could end first, and the harness exit 0).
    long = tmp_path / "long.toml"
    long.write_text('name = "long"\n[[steps]]\nsilence = 600.0\n[expect]\npublished = []\n')
    harness = subprocess.Popen(
        [sys.executable, "-m", "harness", "run", "--transport", "ros", "--real-time", str(long)],
        cwd=ROOT,
        env=_own_roscore_environment(tmp_path),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    started: Set[int] = set()
    deadline = time.monotonic() + 60
    # roscore, its rosmaster and rosout (in sessions of their own), the node, soundDetection
    while len(started) < 5 and time.monotonic() < deadline:
        started |= descendants(harness.pid)
        time.sleep(0.05)
    assert len(started) >= 5
    harness.send_signal(stop_signal)
    _, stderr = harness.communicate(timeout=60)
    assert harness.returncode == status
    assert stderr.endswith(said + "\n")
    alive = {pid for pid in started if Path(f"/proc/{pid}").exists()}
    assert alive == set()


def test_the_route_to_a_given_master_gives_the_address_to_be_reached_at() -> None:
    assert route_address("http://127.0.0.1:11311") == "127.0.0.1"
    assert route_address("http://localhost:1234/") == "127.0.0.1"


def test_config_dir_puts_the_nodes_configuration_where_a_node_elsewhere_can_read_it(tmp_path: Path) -> None:
    shared = tmp_path / "shared"
    shared.mkdir()
    seen = tmp_path / "seen.txt"
    wrapper = tmp_path / "other_node.py"
    wrapper.write_text(
        "import sys\n"
        f"open({str(seen)!r}, 'w').write(sys.argv[1])\n"
        "from speech_event.application import main\n"
        "sys.exit(main(['-c', sys.argv[1], '--recognizer', 'fake']))\n"
    )
    result = _harness(
        _own_roscore_environment(tmp_path),
        "--config-dir",
        str(shared),
        "--node-command",
        f"{sys.executable} {wrapper} {{config}}",
        "scenarios/single_utterance.toml",
    )
    assert result.stdout.splitlines()[-1] == "1 passed, 0 failed", result.stdout + result.stderr
    assert seen.read_text() == str(shared / "speech_event_configuration.ini")
