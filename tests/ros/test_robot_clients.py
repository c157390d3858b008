"""The robot's own clients against our node on a real roscore.

The robot's Behaviour Controller and action clients use their own types (``speechEventSetStatus``,
``speechEventSetLanguage`` and an action of their package): other names, the same fields. ROS 1
matches them by the MD5 of the definitions, so the node must serve them. The tests build those
types with the same build step under another package name and talk to the node through them only.
"""

import importlib
import subprocess
import sys
import xmlrpc.client
from types import ModuleType
from typing import Any, Callable, Dict, Iterator, List, Tuple

import actionlib
import pytest
import rosgraph
import rospy
from actionlib_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticArray
from std_msgs import msg as std_msgs

from fixtures.application import APPLICATION
from fixtures.audio import speak_tones
from fixtures.ros import serves, wait_for
from harness.processes import Processes
from harness.ros.connections import reaches_us
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.ros_interfaces import generate

ROBOT_PACKAGE = "cssr_system"
ACTION = "/speechEvent/recognise_speech_action"


@pytest.fixture(scope="module")
def robot_types(tmp_path_factory: pytest.TempPathFactory) -> Tuple[ModuleType, ModuleType]:
    """The robot's definitions, exactly as reference.md gives them, built as package cssr_system."""
    definitions = tmp_path_factory.mktemp("robot_definitions")
    (definitions / "srv").mkdir()
    (definitions / "action").mkdir()
    (definitions / "srv" / "speechEventSetStatus.srv").write_text("string status\n---\nint8 response\n")
    (definitions / "srv" / "speechEventSetLanguage.srv").write_text("string language\n---\nint8 response\n")
    (definitions / "action" / "recogniseSpeech.action").write_text(
        "float32 wait\n---\nstring transcription\n---\nint8 progress\n"
    )
    built = tmp_path_factory.mktemp("robot_python")
    (built / ROBOT_PACKAGE).mkdir()
    (built / ROBOT_PACKAGE / "__init__.py").write_text("")
    generate(ROBOT_PACKAGE, definitions, built / ROBOT_PACKAGE)
    sys.path.insert(0, str(built))
    return importlib.import_module(f"{ROBOT_PACKAGE}.srv"), importlib.import_module(f"{ROBOT_PACKAGE}.msg")


@pytest.fixture(scope="module")
def node(roscore: Dict[str, str], tmp_path_factory: pytest.TempPathFactory) -> Iterator[Callable[[], str]]:
    """Our node (the fake recognizer serves both languages), checking soundDetection every second;
    what it did, for a failure to show: whether it still runs, which process the master knows as
    /speechEvent, and its log, which says when it was enabled and disabled (unbuffered: read while
    it runs)."""
    work = tmp_path_factory.mktemp("node")
    config = work / "speech_event.ini"
    config.write_text("health_check_period 1\nspeech_pause_period 0.5\nverbose_mode true\n")
    processes = Processes({**roscore, "PYTHONUNBUFFERED": "1"}, work)
    rospy.set_param("/use_sim_time", False)  # wall time: nobody drives /clock here
    ours = processes.start(
        "node", [sys.executable, str(APPLICATION), "-c", str(config), "--recognizer", "fake"]
    )

    def what_it_did() -> str:
        try:
            uri = rosgraph.Master("/probe").lookupNode("/speechEvent")
            answer: Any = xmlrpc.client.ServerProxy(uri).getPid("/probe")  # [code, message, pid]
            known = f"{uri}, pid {answer[2]}"
        except Exception as problem:  # the master or that node does not answer
            known = f"unknown ({problem})"
        running = "runs" if ours.poll() is None else f"exited with {ours.returncode}"
        return (
            f"our node, pid {ours.pid}, {running}; the master's /speechEvent: {known}\n"
            + processes.last_lines("node", 40)
        )

    try:
        # up: its services, and the action it registers last
        wait_for(lambda: serves("/speechEvent/set_enabled"), "the node's set_enabled", 60)
        wait_for(lambda: serves("/speechEvent/set_language"), "the node's set_language", 60)
        wait_for(lambda: serves("/speechEvent/set_language") and _publishes(f"{ACTION}/status"), "the action")
        yield what_it_did
    finally:
        processes.stop_all()


def _publishes(topic: str) -> bool:
    publishers, _, _ = rosgraph.Master("/probe").getSystemState()
    return any(name == topic and nodes for name, nodes in publishers)


def test_the_behaviour_controllers_start_up_checks_find_what_they_look_for(node: Callable[[], str]) -> None:
    master = rosgraph.Master("/behaviourControllerProbe")
    assert master.lookupService("/speechEvent/set_language").startswith("rosrpc://")
    publishers, _, _ = master.getSystemState()
    assert [TEXT_TOPIC, ["/speechEvent"]] in publishers


@pytest.mark.parametrize(
    ("service", "request_text", "response"),
    [
        ("set_language", "English", 1),
        ("set_language", "Kinyarwanda", 1),
        ("set_language", " english ", 1),
        ("set_language", "French", 0),
        ("set_enabled", "true", 1),
        ("set_enabled", "FALSE", 1),
        ("set_enabled", "maybe", 0),
        ("set_enabled", "true", 1),
    ],
)
def test_the_robots_service_types_are_served(
    node: Callable[[], str],
    robot_types: Tuple[ModuleType, ModuleType],
    service: str,
    request_text: str,
    response: int,
) -> None:
    srv, _ = robot_types
    kind = srv.speechEventSetLanguage if service == "set_language" else srv.speechEventSetStatus
    call = rospy.ServiceProxy(f"/speechEvent/{service}", kind)
    assert call(request_text).response == response


def _action_client(robot_types: Tuple[ModuleType, ModuleType]) -> actionlib.SimpleActionClient:
    _, msg = robot_types
    client = actionlib.SimpleActionClient(ACTION, msg.recogniseSpeechAction)
    assert client.wait_for_server(rospy.Duration(30))
    # wait_for_server waits for the server's topics, not for the server to hear the client's goal
    # topic: a goal sent before that connection is up is lost (seen under load, 1 run in 5).
    wait_for(lambda: client.action_client.pub_goal.get_num_connections() > 0, "the node to hear our goals")
    # nor for the node to accept our subscription to its results: one published before is lost
    wait_for(lambda: reaches_us(f"{ACTION}/result"), "the node's results to reach us")
    return client


def test_the_robots_action_client_is_aborted_while_sound_detection_is_down(
    node: Callable[[], str], robot_types: Tuple[ModuleType, ModuleType]
) -> None:
    _, msg = robot_types
    client = _action_client(robot_types)
    client.send_goal(msg.recogniseSpeechGoal(wait=2.0))
    assert client.wait_for_result(rospy.Duration(30))
    outcome = (client.get_state(), client.get_result().transcription)
    assert outcome == (GoalStatus.ABORTED, "Error: soundDetection is down"), node()


def test_the_robots_action_client_gets_the_next_utterance_and_feedback_up_to_100(
    node: Callable[[], str], robot_types: Tuple[ModuleType, ModuleType]
) -> None:
    _, msg = robot_types
    sound_detection = rospy.Publisher(SIGNAL_TOPIC, std_msgs.Float32MultiArray, queue_size=100)
    try:
        wait_for(lambda: sound_detection.get_num_connections() > 0, "the node to connect")
        client = _action_client(robot_types)
        client.send_goal(msg.recogniseSpeechGoal(wait=0.3))  # no speech: succeeds with ""
        assert client.wait_for_result(rospy.Duration(30))
        outcome = (client.get_state(), client.get_result().transcription)
        assert outcome == (GoalStatus.SUCCEEDED, ""), node()
        # What the node sends is read off the feedback topic, connected before the goal is sent. The
        # client's own callback may miss the first and the last: actionlib's SimpleActionClient
        # drops a feedback that comes before send_goal has stored its goal handle (the 0, sent as
        # the goal is accepted, on a busy machine: "a goal handle that we're not tracking") and one
        # that comes after the result (another topic, another connection). The topic carries every
        # goal's feedback (the first goal's 100 came after the connection once): this goal's, by id.
        progress: List[int] = []
        sent: List[Tuple[str, int]] = []
        feedback = rospy.Subscriber(
            f"{ACTION}/feedback",
            msg.recogniseSpeechActionFeedback,
            lambda m: sent.append((m.status.goal_id.id, m.feedback.progress)),
        )
        wait_for(lambda: reaches_us(f"{ACTION}/feedback"), "the feedback topic")
        client.send_goal(msg.recogniseSpeechGoal(wait=5.0), feedback_cb=lambda f: progress.append(f.progress))
        goal_id = client.gh.comm_state_machine.action_goal.goal_id.id
        wait_for(lambda: client.get_state() == GoalStatus.ACTIVE, "the goal to be accepted")
        wait_for(lambda: 10 in progress, "the feedback of the first tenth of the wait")
        speech = speak_tones("yego", 48000)
        for start in range(0, speech.size, 4096):
            sound_detection.publish(std_msgs.Float32MultiArray(data=speech[start : start + 4096].tolist()))
            rospy.sleep(4096 / 48000)
        assert client.wait_for_result(rospy.Duration(30))
        assert (client.get_state(), client.get_result().transcription) == (GoalStatus.SUCCEEDED, "yego")
        wait_for(lambda: (goal_id, 100) in sent, "the last feedback")
        feedback.unregister()
        published = [step for sent_for, step in sent if sent_for == goal_id]
        assert published[:2] == [0, 10] and published == sorted(published)
        assert 10 in progress and progress == [step for step in published if step in progress]
    finally:
        sound_detection.unregister()


def test_diagnostics_reach_rostopic_as_a_diagnostic_array(
    node: Callable[[], str], roscore: Dict[str, str]
) -> None:
    array = rospy.wait_for_message("/diagnostics", DiagnosticArray, timeout=30)
    (status,) = array.status
    values = {value.key: value.value for value in status.values}
    assert status.name == "speechEvent"
    assert values["engine"] == "ToneRecognizer"
    assert values["soundDetection"] in ("no publisher registered", "publisher connected")
    assert status.level == (2 if values["soundDetection"] == "no publisher registered" else 0)
    # and rostopic, as a user runs it, reads it
    echo = subprocess.run(
        ["rostopic", "echo", "-n", "1", "/diagnostics/status[0]/name"],
        env=roscore,
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert echo.stdout.splitlines()[0] == '"speechEvent"', echo.stderr
