"""Plays scenarios to the node on a real roscore: the node and soundDetection are processes of their own.

By default the runner drives ROS time through /clock (/use_sim_time), so messages and error counts
are as exact as in memory although processes start and die in real time: before it moves the clock
on it waits for each real event (the node has received a block, a connection has dropped or been
made), and after each clock step it gives the node's timers time to run. ``real_time`` plays on the
wall clock instead. Every process it starts is stopped again, also on failure or Ctrl-C.
"""

import contextlib
import dataclasses
import math
import os
import shlex
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.parse
import xmlrpc.client
from collections import defaultdict
from contextlib import ExitStack, closing
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Dict, List, Optional, Sequence, Set, Tuple

import actionlib
import rosgraph
import rospy
from actionlib_msgs.msg import GoalStatus
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String

from harness.catalog import engine_for
from harness.memory_runner import run_in_memory
from harness.outcome import Outcome, Published, result_text
from harness.scenario import ReplayError, Scenario
from harness.timeline import CallService, ComeUp, Event, GoDown, Publish, SendGoal, Timeline, build_timeline
from speech_event import SIGNAL_TOPIC, TEXT_TOPIC
from speech_event.adapters.ros import generated_class, master_answers
from speech_event.config import format_config
from speech_event.interfaces.action import ACTION_NAME
from speech_event.interfaces.services import SET_ENABLED_SERVICE, SET_LANGUAGE_SERVICE
from speech_event.messages import (
    RECOGNISE_SPEECH,
    SET_ENABLED,
    SET_LANGUAGE,
    Float32MultiArray,
    ServiceType,
    message_type_name,
)
from speech_event.pipeline.validate import Rejection, validate_signal

ROOT = Path(__file__).resolve().parents[1]
NODE_SCRIPT = ROOT / "scripts" / "speech_event_application.py"
SOUND_DETECTION_SCRIPT = ROOT / "scripts" / "sound_detection_replay.py"
STARTUP_TIMEOUT = 60.0
EVENT_TIMEOUT = 20.0
# After each clock step, the node's timers run; after the step that ends an utterance, its
# recognition runs and its text is published: the runner waits this long for that text.
TIMER_SETTLE = 0.03
TEXT_WAIT = 1.0
# Our node sets this to the ROS time it started (its health checks count from there).
START_TIME_PARAM = "/speechEvent/start_time"
# Real time: how long the harness needs, after the node is ready, before the scenario's t = 0.
ALIGN_MARGIN = 0.5
# Real time: the node's checks come this much before the scenario's multiples of the period. In
# sim time (and in memory) a check due at T runs before the events at T; so here too.
CHECK_LEAD = 0.05
SERVICES: Dict[str, ServiceType] = {SET_ENABLED_SERVICE: SET_ENABLED, SET_LANGUAGE_SERVICE: SET_LANGUAGE}
# actionlib's terminal states, as a scenario's results name them.
GOAL_STATES = {
    GoalStatus.SUCCEEDED: "succeeded",
    GoalStatus.ABORTED: "aborted",
    GoalStatus.PREEMPTED: "preempted",
    GoalStatus.RECALLED: "recalled",
    GoalStatus.REJECTED: "rejected",
    GoalStatus.LOST: "lost",
}


def _wait_until(condition: Callable[[], bool], what: str, timeout: float = EVENT_TIMEOUT) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            raise ReplayError(f"gave up after {timeout:.0f} s waiting for {what}")
        time.sleep(0.002)


def descendants(pid: int) -> Set[int]:
    """Every live process below ``pid``, from /proc: roslaunch starts rosmaster and rosout in
    sessions of their own, out of reach of a signal to roscore's process group."""
    parents: Dict[int, int] = {}
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            parents[int(stat.parent.name)] = int(stat.read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, IndexError, ValueError):  # the process ended while being read
            continue
    found: Set[int] = set()
    frontier = {pid}
    while frontier:
        frontier = {child for child, parent in parents.items() if parent in frontier}
        found |= frontier
    return found


def free_port() -> int:
    with closing(socket.socket(socket.AF_INET, socket.SOCK_STREAM)) as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


class Processes:
    """Every process the runner starts, each in its own process group, all stopped at the end."""

    def __init__(self, environment: Dict[str, str], log_dir: Path) -> None:
        self._environment = environment
        self._log_dir = log_dir
        self._started: List[subprocess.Popen] = []  # type: ignore[type-arg]

    def start(self, name: str, command: Sequence[str], talk: bool = False) -> "subprocess.Popen[str]":
        # The child holds its own copy of the log's descriptor; ours closes once it has started.
        with open(self.log(name), "a") as log:
            try:
                process = subprocess.Popen(
                    list(command),
                    env=self._environment,
                    stdin=subprocess.PIPE if talk else subprocess.DEVNULL,
                    stdout=subprocess.PIPE if talk else log,
                    stderr=log,
                    text=True,
                    start_new_session=True,
                )
            except OSError as problem:  # no such executable, not executable
                raise ReplayError(f"cannot start the {name} ({command[0]}): {problem.strerror}") from None
        self._started.append(process)
        return process

    def log(self, name: str) -> Path:
        return self._log_dir / f"{name}.log"

    def last_lines(self, name: str, count: int = 15) -> str:
        """The end of a process's log, for an error that must say why it died."""
        try:
            lines = self.log(name).read_text(errors="replace").splitlines()
        except OSError:
            return "(no output)"
        return "\n".join(lines[-count:]) or "(no output)"

    def stop(self, process: "subprocess.Popen[str]", grace: float = 5.0) -> None:
        if process.poll() is not None:
            return
        family = descendants(process.pid)  # before the signal: orphans are no longer below it
        with contextlib.suppress(ProcessLookupError):  # it may have gone already
            os.killpg(process.pid, signal.SIGINT)
        try:
            process.wait(grace)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()
        deadline = time.monotonic() + grace
        while any(Path(f"/proc/{pid}").exists() for pid in family) and time.monotonic() < deadline:
            time.sleep(0.05)  # a clean roscore stops its rosmaster and rosout itself
        for pid in family:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)

    def stop_all(self) -> None:
        for process in reversed(self._started):
            self.stop(process)


@dataclass
class RosOptions:
    real_time: bool = False
    node_command: Optional[str] = None
    base_config: Optional[str] = None
    # Where the node's configuration file is written (a folder a node on another host can read).
    config_dir: Optional[str] = None


def route_address(master_uri: str) -> str:
    """This host's address on the route to the master (no packet is sent: UDP connect only)."""
    address = urllib.parse.urlsplit(master_uri)
    with closing(socket.socket(socket.AF_INET, socket.SOCK_DGRAM)) as probe:
        probe.connect((address.hostname or "127.0.0.1", address.port or 11311))
        return str(probe.getsockname()[0])


class RosReplay:
    """One roscore (its own, or the one ROS_MASTER_URI names) and the harness's own ROS node."""

    def __init__(self, stack: ExitStack, options: RosOptions) -> None:
        self._options = options
        self._work = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="speech_event_ros_")))
        environment = dict(os.environ)
        environment["ROS_HOME"] = str(self._work / "ros_home")
        environment["ROS_LOG_DIR"] = str(self._work / "ros_log")
        environment["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), environment.get("PYTHONPATH")]))
        self.processes = Processes(environment, self._work)
        stack.callback(self.processes.stop_all)
        if "ROS_MASTER_URI" not in os.environ:
            # Our own master, on loopback: everything of this replay stays on this host.
            port = free_port()
            environment["ROS_MASTER_URI"] = f"http://127.0.0.1:{port}"
            environment.setdefault("ROS_IP", "127.0.0.1")
            self.processes.start("roscore", ["roscore", "-p", str(port)])
        elif not ({"ROS_IP", "ROS_HOSTNAME"} & set(environment)):
            # A given master, maybe on another host: be reachable from there (the user's ROS_IP
            # or ROS_HOSTNAME wins).
            environment["ROS_IP"] = route_address(environment["ROS_MASTER_URI"])
        os.environ.update(
            {key: environment[key] for key in ("ROS_MASTER_URI", "ROS_IP") if key in environment}
        )
        self._master = rosgraph.Master("/speechEventReplay", master_uri=environment["ROS_MASTER_URI"])
        _wait_until(
            lambda: master_answers(environment["ROS_MASTER_URI"]),
            "the ROS master at " + environment["ROS_MASTER_URI"],
            STARTUP_TIMEOUT,
        )
        rospy.set_param("/use_sim_time", not options.real_time)
        rospy.init_node("speechEventReplay", disable_signals=True)
        self._clock = rospy.Publisher("/clock", Clock, queue_size=10, latch=True)
        self._outcome = Outcome()
        self._now = 0.0
        self._wall_start = time.monotonic()
        self._text_subscriber = rospy.Subscriber(TEXT_TOPIC, String, self._on_text, queue_size=None)
        action = generated_class(RECOGNISE_SPEECH.name + "Action", "msg")
        self._action_client = actionlib.ActionClient(ACTION_NAME, action)
        # A goal handle must be kept, or actionlib stops tracking its goal.
        self._goals: List[actionlib.ClientGoalHandle] = []

    def _scenario_time(self) -> float:
        """Now on the scenario clock: the last clock step in sim time, the wall clock in real time."""
        return time.monotonic() - self._wall_start if self._options.real_time else self._now

    def _on_text(self, message: String) -> None:
        self._outcome.published.append(Published(self._scenario_time(), message.data))

    # -- the services and the action ------------------------------------------------------------

    def _call(self, event: CallService) -> None:
        service = SERVICES[event.service]
        ros_service = generated_class(service.name, "srv")
        try:
            rospy.wait_for_service(event.service, timeout=EVENT_TIMEOUT)
            request = ros_service._request_class(**dataclasses.asdict(event.request))  # type: ignore[call-overload]
            response = rospy.ServiceProxy(event.service, ros_service)(request)
        except (rospy.ROSException, rospy.ServiceException) as problem:
            raise ReplayError(f"calling {event.service}: {problem}") from None
        self._outcome.responses.append(int(response.response))

    def _send_goal(self, event: SendGoal) -> None:
        goal_type = generated_class(RECOGNISE_SPEECH.name + "Goal", "msg")

        def transition(handle: actionlib.ClientGoalHandle) -> None:
            if handle.get_comm_state() == actionlib.CommState.DONE:
                state = GOAL_STATES.get(handle.get_goal_status(), "unknown")
                result = handle.get_result()
                transcription = result.transcription if result is not None else ""
                self._outcome.results.append(
                    Published(self._scenario_time(), result_text(state, transcription))
                )

        handle = self._action_client.send_goal(goal_type(**dataclasses.asdict(event.goal)), transition)
        self._goals.append(handle)
        # Accepted at this clock time: the clock must not move before the node has it.
        _wait_until(
            lambda: handle.get_comm_state() in (actionlib.CommState.ACTIVE, actionlib.CommState.DONE),
            "the node to accept the action goal",
        )

    def _catch_up(self, expected: Outcome, played: int, at_the_end: bool = False) -> None:
        """Wait (a while) for what the node published in memory by now, before the next event.

        In real time waiting would shift the events after it, so it waits only at the end."""
        if self._options.real_time and not at_the_end:
            return

        def due(items: List[Published]) -> int:
            return sum(1 for item in items if item.time <= self._now and item.played <= played)

        texts, results = due(expected.published), due(expected.results)
        deadline = time.monotonic() + TEXT_WAIT
        while time.monotonic() < deadline and (
            len(self._outcome.published) < texts or len(self._outcome.results) < results
        ):
            time.sleep(0.002)

    # -- the clock --------------------------------------------------------------------------------

    def _set_clock(self, when: float) -> None:
        self._now = when
        if self._options.real_time:
            time.sleep(max(0.0, self._wall_start + when - time.monotonic()))
        else:
            self._clock.publish(Clock(clock=rospy.Time.from_sec(when)))
            time.sleep(TIMER_SETTLE)

    # -- the node under test ----------------------------------------------------------------------

    def _start_node(self, scenario: Scenario) -> "subprocess.Popen[str]":
        engine, config = engine_for(scenario.recognizer, scenario.config)
        config_dir = Path(self._options.config_dir) if self._options.config_dir else self._work
        config_path = config_dir / "speech_event_configuration.ini"
        config_path.write_text(format_config(config))
        if self._options.node_command:
            # Split first, then fill in: a path with spaces stays one word, other braces stay as written.
            fill = {"{config}": str(config_path), "{recognizer}": engine}
            command = [_filled(word, fill) for word in shlex.split(self._options.node_command)]
        else:
            command = [
                sys.executable,
                str(NODE_SCRIPT),
                "-c",
                str(config_path),
                "--recognizer",
                engine,
            ]
        return self.processes.start("node", command)

    def _wait_for_the_action_server(self) -> None:
        """wait_for_server waits for the server's topics only: a goal sent before the node hears the
        goal topic is lost, so this waits for that connection too."""
        if not self._action_client.wait_for_server(rospy.Duration(EVENT_TIMEOUT)):
            raise ReplayError(f"the node serves no action {ACTION_NAME}")
        deadline = time.monotonic() + EVENT_TIMEOUT
        while self._action_client.pub_goal.get_num_connections() == 0:
            if time.monotonic() > deadline:
                raise ReplayError(f"the node does not hear the goals of {ACTION_NAME}")
            time.sleep(0.01)

    def _wait_for_node(self, node: "subprocess.Popen[str]") -> None:
        deadline = time.monotonic() + STARTUP_TIMEOUT
        while not self._node_ready():
            status = node.poll()
            if status is not None:
                raise ReplayError(
                    f"the node under test exited with status {status} before it subscribed to "
                    f"{SIGNAL_TOPIC}; its last output:\n{self.processes.last_lines('node')}"
                )
            if time.monotonic() > deadline:
                raise ReplayError(f"gave up after {STARTUP_TIMEOUT:.0f} s waiting for the node to subscribe")
            time.sleep(0.01)

    def _align_with_the_node(self, period: float) -> None:
        """Real time: start the scenario clock at one of the node's health-check instants, so its
        checks fall at multiples of the period on the scenario clock, as in sim time. Our node says
        when it started (its checks count from there); for another, when it became ready will do."""
        started = float(rospy.get_param(START_TIME_PARAM, time.time()))
        checks_passed = math.ceil((time.time() + ALIGN_MARGIN - started) / period)
        start = started + checks_passed * period + CHECK_LEAD
        self._wall_start = time.monotonic() + (start - time.time())
        time.sleep(max(0.0, self._wall_start - time.monotonic()))
        self._outcome = Outcome()  # what the node said before the scenario's t = 0 is no part of it

    def _node_uri(self) -> str:
        _, subscribers, _ = self._master.getSystemState()
        nodes = [node for topic, names in subscribers if topic == SIGNAL_TOPIC for node in names]
        others = [node for node in nodes if node != "/speechEventReplay"]
        if not others:
            raise ReplayError(f"no node subscribes to {SIGNAL_TOPIC}")
        return str(self._master.lookupNode(others[0]))

    def _node_ready(self) -> bool:
        try:
            _, subscribers, _ = self._master.getSystemState()
        except Exception:
            return False
        listening = any(topic == SIGNAL_TOPIC and names for topic, names in subscribers)
        return listening and self._text_subscriber.get_num_connections() > 0

    def _live_connections(self, node_uri: str) -> List[Any]:
        """The node's live connections on the signal topic, as getBusStats gives them:
        [connection id, bytes received, messages received, drop estimate, connected]."""
        proxy = xmlrpc.client.ServerProxy(node_uri)
        try:
            stats: Any = proxy.getBusStats("/speechEventReplay")
        except (OSError, xmlrpc.client.Error) as problem:  # the node's host or process gone
            raise ReplayError(
                f"the node under test at {node_uri} did not answer getBusStats: {problem}"
            ) from None
        subscriptions = stats[2][1]
        return [
            c for topic, connections in subscriptions if topic == SIGNAL_TOPIC for c in connections if c[4]
        ]

    # -- playing ----------------------------------------------------------------------------------

    def play(self, scenario: Scenario) -> Outcome:
        timeline = build_timeline(scenario)
        # What the node does in memory tells when to wait for what; it is never what is compared.
        expected = run_in_memory(scenario)
        self._outcome = Outcome()
        self._goals = []
        self._set_clock(0.0)
        with contextlib.suppress(KeyError):
            rospy.delete_param(START_TIME_PARAM)  # the last scenario's node said it
        node = self._start_node(scenario)
        self._wait_for_node(node)
        sends_goals = any(isinstance(event, SendGoal) for event in timeline.events)
        if sends_goals:
            self._wait_for_the_action_server()
        stand_in = _StandIn(self.processes, scenario.source, self._options.base_config, self._node_uri())
        closing_times = _utterance_closing_times(scenario, timeline)
        events_at: Dict[float, List[Tuple[int, Event]]] = defaultdict(list)
        for index, event in enumerate(timeline.events):
            events_at[event.time].append((index, event))
        visits = _times_to_visit(scenario, timeline, closing_times, expected)
        if self._options.real_time:
            self._align_with_the_node(scenario.config.health_check_period)
        played = 0
        for when in visits:
            self._set_clock(when)
            for index, event in events_at.get(when, []):
                self._catch_up(expected, played)
                if isinstance(event, CallService):
                    self._call(event)
                elif isinstance(event, SendGoal):
                    self._send_goal(event)
                else:
                    stand_in.play(index, event, self._live_connections)
                played = index + 1
            self._catch_up(expected, played, at_the_end=when == visits[-1])
        # What was observed by the end of the timeline, before anything is torn down: a health
        # check between stopping soundDetection and stopping the node is no part of the scenario.
        outcome, self._outcome = self._outcome, Outcome()
        stand_in.stop()
        self.processes.stop(node)
        return outcome


class _StandIn:
    """The soundDetection processes of a replay: started, told to publish, shut down or killed.

    While soundDetection is down the next incarnation is already started, as a ROS node that is no
    publisher yet (under a name of its own, so a crashed one's stale registration stays for the
    node to find), and only advertises when the outage ends: a restart takes no scenario time,
    also in real time.
    """

    def __init__(
        self, processes: Processes, scenario_path: str, base_config: Optional[str], node_uri: str
    ) -> None:
        self._processes = processes
        self._command = [sys.executable, str(SOUND_DETECTION_SCRIPT), scenario_path]
        if base_config:
            self._command += ["-c", base_config]
        self._node_uri = node_uri
        self._incarnations = 0
        self._process = self._up(self._launch())
        self._next: Optional[subprocess.Popen[str]] = None
        self._sent = 0  # messages this incarnation has published
        self._intruders: List[subprocess.Popen[str]] = []  # the wrong-type publishers started

    def _launch(self) -> "subprocess.Popen[str]":
        name = "soundDetection" if self._incarnations == 0 else f"soundDetection{self._incarnations}"
        self._incarnations += 1
        process = self._processes.start("sound_detection", [*self._command, "--name", name], talk=True)
        self._expect(process, "started")
        return process

    def _up(self, process: "subprocess.Popen[str]") -> "subprocess.Popen[str]":
        self._tell(process, "advertise")
        self._expect(process, "ready")
        return process

    @staticmethod
    def _expect(process: "subprocess.Popen[str]", expected: str) -> None:
        line = process.stdout.readline().strip() if process.stdout else ""
        if line != expected:
            raise ReplayError(f"the soundDetection stand-in said {line!r}, expected {expected!r}")

    @staticmethod
    def _tell(process: "subprocess.Popen[str]", command: str) -> None:
        assert process.stdin is not None
        process.stdin.write(command + "\n")
        process.stdin.flush()

    def play(self, index: int, event: Event, live_connections: Callable[[str], List[Any]]) -> None:
        if isinstance(event, Publish) and message_type_name(event.message) == Float32MultiArray._type:
            self._tell(self._process, f"publish {index}")
            self._expect(self._process, f"published {index}")
            self._sent += 1
            sent = self._sent
            _wait_until(
                lambda: any(int(c[2]) >= sent for c in live_connections(self._node_uri)),
                f"the node to receive message {sent}",
            )
        elif isinstance(event, Publish):
            # Not waited for here: starting a ROS node takes a second or more, which in real time
            # would stop the scenario's next blocks for longer than a pause. Checked at the end.
            self._intruders.append(
                self._processes.start("wrong_type", [*self._command, "--wrong-type", str(index)])
            )
        elif isinstance(event, GoDown):
            if event.kind == "crash":
                os.killpg(self._process.pid, signal.SIGKILL)
            else:
                self._tell(self._process, "shutdown")
            self._process.wait(EVENT_TIMEOUT)
            _wait_until(lambda: not live_connections(self._node_uri), "the node to lose soundDetection")
            self._next = self._launch()
        elif isinstance(event, ComeUp):
            self._process = self._up(self._next or self._launch())
            self._next = None
            self._sent = 0

    def stop(self) -> None:
        for process in (self._process, self._next):
            if process is not None:
                self._processes.stop(process)
        for intruder in self._intruders:
            if intruder.wait(EVENT_TIMEOUT) != 0:
                raise ReplayError("the wrong-type publisher failed; see its log")


def _filled(word: str, values: Dict[str, str]) -> str:
    for placeholder, value in values.items():
        word = word.replace(placeholder, value)
    return word


def _utterance_closing_times(scenario: Scenario, timeline: Timeline) -> Set[float]:
    """Times at which the node ends an utterance: the pause after the last block of each burst."""
    pause = scenario.config.speech_pause_period
    max_samples = int(scenario.config.max_message_length * scenario.config.sample_rate)
    arrivals = [
        event.time
        for event in timeline.events
        if isinstance(event, Publish)
        and not isinstance(validate_signal(event.message, max_samples), Rejection)
    ]
    return {
        arrival + pause
        for arrival, following in zip(arrivals, [*arrivals[1:], float("inf")])
        if following - arrival >= pause
    }


def _times_to_visit(
    scenario: Scenario, timeline: Timeline, closing_times: Set[float], expected: Outcome
) -> List[float]:
    """Every time something happens: events, health checks, utterance ends, and whatever else made
    the node publish or end a goal in memory (an action goal's wait running out)."""
    period = scenario.config.health_check_period
    checks = {period * k for k in range(1, int(timeline.end / period) + 1)}
    events = {event.time for event in timeline.events}
    outputs = {item.time for item in [*expected.published, *expected.results]}
    return sorted({*events, *checks, *closing_times, *outputs, timeline.end})
