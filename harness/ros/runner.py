"""Plays scenarios to the node on a real roscore: the node and soundDetection are processes of their own.

By default the runner drives ROS time through /clock (/use_sim_time), so messages and error counts
are as exact as in memory although processes start and die in real time: before it moves the clock
on it waits for each real event (the node has received a block or the clock step, a connection
has dropped or been made, a health check has published its /diagnostics), so that how busy the
machine is changes nothing it compares. ``real_time`` plays on the wall clock instead. Every
process it starts is stopped again, also on failure or Ctrl-C.

The walk over the timeline is the in-memory runner's (harness/player.py); where the clock stops
besides the events, and what is waited for there, comes from harness/schedule.py, and
soundDetection is harness/ros/stand_in.py's processes.
"""

import contextlib
import dataclasses
import math
import os
import shlex
import socket
import subprocess
import sys
import tempfile
import time
import urllib.parse
import xmlrpc.client
from contextlib import ExitStack, closing
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Dict, List, Optional, Set

import actionlib
import rosgraph
import rospy
from actionlib_msgs.msg import GoalStatus
from diagnostic_msgs.msg import DiagnosticArray
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String

from harness.catalog import engine_for
from harness.outcome import REAL_TIME, SIM_TIME, Outcome, Published, result_text
from harness.player import play
from harness.processes import EVENT_TIMEOUT, Processes, ReplayError, free_port, wait_until
from harness.ros.connections import topics_sent_to
from harness.ros.stand_in import StandIns
from harness.scenario import Scenario
from harness.schedule import (
    CLOCK_RESOLUTION,
    TEXT_DEADLINE,
    TEXT_WAIT_AFTER_MISS,
    TIMER_SETTLE,
    HealthChecks,
    ScenarioWallClock,
    Schedule,
    block_just_played,
)
from harness.timeline import ComeUp, Event, GoDown, SendGoal, build_timeline
from speech_event import PARTIAL_TOPIC, SIGNAL_TOPIC, TEXT_TOPIC, TRANSCRIPT_TOPIC
from speech_event.adapters.ros import generated_class, master_answers, transcript_from_ros
from speech_event.config import format_config
from speech_event.interfaces.action import ACTION_NAME
from speech_event.interfaces.diagnostics import DIAGNOSTICS_TOPIC
from speech_event.interfaces.services import SET_ENABLED_SERVICE, SET_GRAMMAR_SERVICE, SET_LANGUAGE_SERVICE
from speech_event.messages import (
    RECOGNISE_SPEECH,
    SET_ENABLED,
    SET_GRAMMAR,
    SET_LANGUAGE,
    RecogniseSpeechGoal,
    ServiceType,
    TranscriptMessage,
)

ROOT = Path(__file__).resolve().parents[2]
CLOCK_TOPIC = "/clock"
STARTUP_TIMEOUT = 60.0
# Our node sets this to the ROS time it started (its health checks count from there).
START_TIME_PARAM = "/speechEvent/start_time"
SERVICES: Dict[str, ServiceType] = {
    SET_ENABLED_SERVICE: SET_ENABLED,
    SET_LANGUAGE_SERVICE: SET_LANGUAGE,
    SET_GRAMMAR_SERVICE: SET_GRAMMAR,
}
# actionlib's terminal states, as a scenario's results name them.
GOAL_STATES = {
    GoalStatus.SUCCEEDED: "succeeded",
    GoalStatus.ABORTED: "aborted",
    GoalStatus.PREEMPTED: "preempted",
    GoalStatus.RECALLED: "recalled",
    GoalStatus.REJECTED: "rejected",
    GoalStatus.LOST: "lost",
}


@dataclass
class RosOptions:
    real_time: bool = False
    node_command: Optional[str] = None
    base_config: Optional[str] = None
    # Where the node's configuration file is written (a folder a node on another host can read).
    config_dir: Optional[str] = None
    # The most seconds to wait for a text the node published by then in memory (harness/schedule.py).
    text_deadline: float = TEXT_DEADLINE


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
        wait_until(
            lambda: master_answers(environment["ROS_MASTER_URI"]),
            "the ROS master at " + environment["ROS_MASTER_URI"],
            STARTUP_TIMEOUT,
        )
        rospy.set_param("/use_sim_time", not options.real_time)
        rospy.init_node("speechEventReplay", disable_signals=True)
        self._clock = rospy.Publisher(CLOCK_TOPIC, Clock, queue_size=10, latch=True)
        self._outcome = self._new_outcome()
        self._now = 0.0
        self._wall = ScenarioWallClock()  # the scenario clock in real time
        self._text_subscriber = rospy.Subscriber(TEXT_TOPIC, String, self._on_text, queue_size=None)
        # When the node's latest health check ran (ROS time), from the /diagnostics it publishes with each.
        self._checked_at = -math.inf
        self._diagnostics = rospy.Subscriber(
            DIAGNOSTICS_TOPIC, DiagnosticArray, self._on_diagnostics, queue_size=None
        )
        rospy.Subscriber(PARTIAL_TOPIC, String, self._on_partial, queue_size=None)
        transcript = generated_class(TranscriptMessage._type, "msg")
        rospy.Subscriber(TRANSCRIPT_TOPIC, transcript, self._on_transcript, queue_size=None)
        action = generated_class(RECOGNISE_SPEECH.name + "Action", "msg")
        self._action_client = actionlib.ActionClient(ACTION_NAME, action)
        # A goal handle must be kept, or actionlib stops tracking its goal.
        self._goals: List[actionlib.ClientGoalHandle] = []
        self._events: List[Event] = []  # the timeline being played, and its pause (played_late)
        self._pause = 0.0
        self._schedule = Schedule(Outcome())  # of the scenario being played
        self._compares_partials = False  # whether it compares partial texts
        self._timers_fired: Set[float] = set()  # its stops: when the node's timers fired in memory
        self._node_uri: Optional[str] = None  # the node under test, once it runs
        # When the node under test checks soundDetection; None: it publishes no /diagnostics
        # (another node than ours), and the replay gives each of its timers TIMER_SETTLE instead.
        self._checks: Optional[HealthChecks] = None

    def _scenario_time(self) -> float:
        """Now on the scenario clock: the last clock step in sim time, the wall clock in real time."""
        return self._wall.now() if self._options.real_time else self._now

    def _new_outcome(self) -> Outcome:
        return Outcome(clock=REAL_TIME if self._options.real_time else SIM_TIME)

    def _on_text(self, message: String) -> None:
        self._outcome.published.append(Published(self._scenario_time(), message.data))

    def _on_partial(self, message: String) -> None:
        self._outcome.partials.append(Published(self._scenario_time(), message.data))

    def _on_transcript(self, message: Any) -> None:
        self._outcome.transcripts.append(transcript_from_ros(message))

    def _on_diagnostics(self, message: Any) -> None:
        self._checked_at = max(self._checked_at, message.header.stamp.to_sec())

    # -- the walk's runner (harness/player.py): the clock, the services and the action ----------

    def advance_to(self, when: float) -> None:
        self._now = when
        if self._options.real_time:
            self._wall.sleep_until(when)
            return
        # The node hears /clock and the signal on connections of their own: a block sent after a
        # clock step may be read before the step on a busy machine (its arrival time then wrong),
        # so the step must have reached the node first. rospy counts a message as received before
        # its callback sets the time, and calls back on the connection's one thread: the step is
        # sent twice, and the second counted means the first one's callback has run.
        received = self._clock_received()
        for sent in (1, 2):
            self._clock.publish(Clock(clock=rospy.Time.from_sec(when)))
            if received is not None:
                wait_until(
                    lambda: (self._clock_received() or 0) >= received + sent,  # noqa: B023 (called here)
                    f"the node under test to receive the clock step to {when:.3f} s",
                )
        # The node's timers run on threads of their own once the step has reached it. A health
        # check asks the master what it finds at the time it runs: one that ran after the events
        # of a later time (soundDetection's crash) would say what it found then, so the clock
        # moves on only once the check has published its /diagnostics. The node's other rules
        # hold however late their timers run (a block that comes after the pause ends the
        # utterance before it, speech_event/turns/turn_taking.py), and what they publish is waited
        # for by settle.
        if received is None or (self._checks is None and when in self._timers_fired):
            time.sleep(TIMER_SETTLE)  # nothing of the node's to wait for: its start, or another node
        elif self._checks is not None and self._checks.at(when):
            try:
                wait_until(
                    lambda: self._checked_at >= when - CLOCK_RESOLUTION,
                    f"the node under test's health check at {when:.3f} s (its /diagnostics)",
                )
            except ReplayError as problem:
                raise ReplayError(
                    f"{problem}; the node's last lines:\n{self.processes.last_lines('node')}"
                ) from None

    def _clock_received(self) -> Optional[int]:
        """The clock messages the node under test has received; None before it runs or when it
        does not hear /clock (a node timed by the wall clock)."""
        if self._node_uri is None:
            return None
        connections = self._live_connections(self._node_uri, CLOCK_TOPIC)
        return sum(int(connection[2]) for connection in connections) if connections else None

    def settle(self, played: int, final: bool) -> None:
        """Wait (a while) for what the node published in memory by now, before the next event.

        In real time waiting would shift the events after it, so it waits only at the end; after
        a block that went out late before a silence, the events after it move later (played_late)."""
        if final or not self._options.real_time:
            self._wait_for_due(played)
            return
        block = block_just_played(self._events, played, self._now)
        if block is not None and len(self._goals) == len(self._outcome.results):  # no goal waits
            self._wall.played_late(*block, self._pause)

    def wait_for_text(self, played: int) -> None:
        """In sim time settle has waited already; in real time the call's answer moves the events
        after it later by the wait (ScenarioWallClock)."""
        self._wait_for_due(played)

    def _wait_for_due(self, played: int) -> None:
        due = self._schedule.due(self._now, played)
        # In real time when a partial comes decides what it says: never compared. In sim time a
        # partial runs only when the worker is idle, which a speculation still running on the wall
        # clock may keep it from (in memory recognition takes no time): waited for only where the
        # scenario compares partials (short_pause_joins on fixture-parakeet waited 30 s for one).
        if self._options.real_time or not self._compares_partials:
            due = dataclasses.replace(due, partials=())
        patience = TEXT_WAIT_AFTER_MISS if self._outcome.gave_up else self._options.text_deadline
        gave_up = due.wait(self._outcome, patience, self._scenario_time)
        if gave_up:
            said = (
                ""
                if self._outcome.gave_up
                else "; the node's last lines:\n" + self.processes.last_lines("node")
            )
            self._outcome.gave_up.append(gave_up + said)

    def call(self, service: str, request: object) -> None:
        ros_service = generated_class(SERVICES[service].name, "srv")
        try:
            rospy.wait_for_service(service, timeout=EVENT_TIMEOUT)
            ros_request = ros_service._request_class(**dataclasses.asdict(request))  # type: ignore[call-overload]
            response = rospy.ServiceProxy(service, ros_service)(ros_request)
        except (rospy.ROSException, rospy.ServiceException) as problem:
            raise ReplayError(f"calling {service}: {problem}") from None
        self._outcome.responses.append(int(response.response))
        if self._options.real_time:
            self._wall.answered(self._now)

    def send_goal(self, goal: RecogniseSpeechGoal) -> None:
        goal_type = generated_class(RECOGNISE_SPEECH.name + "Goal", "msg")

        def transition(handle: actionlib.ClientGoalHandle) -> None:
            if handle.get_comm_state() == actionlib.CommState.DONE:
                state = GOAL_STATES.get(handle.get_goal_status(), "unknown")
                result = handle.get_result()
                transcription = result.transcription if result is not None else ""
                self._outcome.results.append(
                    Published(self._scenario_time(), result_text(state, transcription))
                )

        handle = self._action_client.send_goal(goal_type(**dataclasses.asdict(goal)), transition)
        self._goals.append(handle)
        # Accepted at this clock time: the clock must not move before the node has it.
        wait_until(
            lambda: handle.get_comm_state() in (actionlib.CommState.ACTIVE, actionlib.CommState.DONE),
            "the node to accept the action goal",
        )
        if self._options.real_time:
            self._wall.answered(self._now)

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
                "-m",
                "speech_event",  # the package this Python sees: the checkout's, or an installed one
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
            time.sleep(0.05)  # a node takes most of a second to start: no need to ask the master more

    def _align_with_the_node(self, period: float) -> None:
        """Real time: start the scenario clock at one of the node's health-check instants, so its
        checks fall at multiples of the period on the scenario clock, as in sim time. Our node says
        when it started (its checks count from there); for another, when it became ready will do.
        Where soundDetection never goes down a check finds it up whenever it runs, and publishes
        nothing: the clock starts at once (waiting for the node's first check, 5 s after its start,
        cost each such scenario about 4 s)."""
        if not any(isinstance(event, (GoDown, ComeUp)) for event in self._events):
            self._wall.start_now(period)
        else:
            self._wall.start(time.time() if self._checks is None else self._checks.started_at, period)
        self._outcome = self._new_outcome()  # what the node said before the scenario's t = 0 is no part of it

    def _node_name(self) -> str:
        """The node under test: the one that subscribes to soundDetection's topic besides ours."""
        _, subscribers, _ = self._master.getSystemState()
        nodes = [node for topic, names in subscribers if topic == SIGNAL_TOPIC for node in names]
        others = [node for node in nodes if node != "/speechEventReplay"]
        if not others:
            raise ReplayError(f"no node subscribes to {SIGNAL_TOPIC}")
        return str(others[0])

    def _find_node(self) -> str:
        return str(self._master.lookupNode(self._node_name()))

    def _health_checks(self, period: float) -> Optional[HealthChecks]:
        """When our node checks soundDetection (it says when it started; its checks count from
        there); None for a node that publishes no /diagnostics.

        Ours advertises /diagnostics before it listens, and says when it started once its start
        has ended: waited for, so nothing is played before. Read too soon, the default stood in
        for it, on a busy machine the node's start took the time of 'hello', and its checks came
        0.43 s after the replay's (outage_crash on ROS)."""
        publishers, _, _ = self._master.getSystemState()
        node = self._node_name()
        if not any(topic == DIAGNOSTICS_TOPIC and node in names for topic, names in publishers):
            return None
        said = f"the node under test to say when it started ({START_TIME_PARAM})"
        wait_until(lambda: rospy.has_param(START_TIME_PARAM), said)
        return HealthChecks(float(rospy.get_param(START_TIME_PARAM)), period)

    def _wait_until_the_node_sends_to_us(self, node_uri: str) -> None:
        """Every topic the node under test publishes and the replay hears, connected as the node
        sees it (harness/ros/connections.py: our own count may also still hold the last
        scenario's node)."""
        publishers, subscribers, _ = self._master.getSystemState()
        node = self._node_name()
        ours = rospy.get_caller_id()
        topics = {topic for topic, names in publishers if node in names} & {
            topic for topic, names in subscribers if ours in names
        }

        def connected() -> bool:
            try:
                return topics <= topics_sent_to(node_uri, ours)
            except (OSError, xmlrpc.client.Error) as problem:  # the node's host or process gone
                raise ReplayError(
                    f"the node under test at {node_uri} did not answer getBusInfo: {problem}"
                ) from None

        wait_until(connected, f"the node under test to connect {', '.join(sorted(topics))} to the replay")

    def _node_ready(self) -> bool:
        try:
            _, subscribers, _ = self._master.getSystemState()
        except Exception:
            return False
        listening = any(topic == SIGNAL_TOPIC and names for topic, names in subscribers)
        return listening and self._text_subscriber.get_num_connections() > 0

    def _node_connections(self) -> List[Any]:
        """The live connections of this scenario's node on the signal topic."""
        if self._node_uri is None:
            raise ReplayError("no node under test is up")
        return self._live_connections(self._node_uri)

    def _live_connections(self, node_uri: str, topic: str = SIGNAL_TOPIC) -> List[Any]:
        """The node's live connections on ``topic`` it subscribes to, as getBusStats gives them:
        [connection id, bytes received, messages received, drop estimate, connected]."""
        proxy = xmlrpc.client.ServerProxy(node_uri)
        try:
            stats: Any = proxy.getBusStats("/speechEventReplay")
        except (OSError, xmlrpc.client.Error) as problem:  # the node's host or process gone
            raise ReplayError(
                f"the node under test at {node_uri} did not answer getBusStats: {problem}"
            ) from None
        subscriptions = stats[2][1]
        return [c for name, connections in subscriptions if name == topic for c in connections if c[4]]

    # -- playing ----------------------------------------------------------------------------------

    def play(self, scenario: Scenario) -> Outcome:
        timeline = build_timeline(scenario)
        self._events, self._pause = timeline.events, scenario.config.speech_pause_period
        self._schedule = Schedule.of(scenario)
        self._compares_partials = scenario.expected_partials is not None
        self._timers_fired = set(self._schedule.stops)
        self._outcome = self._new_outcome()
        self._goals = []
        self._node_uri = None  # the last scenario's node is gone, also when it failed
        self.advance_to(0.0)
        with contextlib.suppress(KeyError):
            rospy.delete_param(START_TIME_PARAM)  # the last scenario's node said it
        node = self._start_node(scenario)
        # soundDetection's process starts beside the node's (each takes a second of Python and rospy)
        stand_ins = StandIns(
            self.processes,
            scenario.source,
            self._options.base_config,
            self._node_connections,
            outages=any(isinstance(event, GoDown) for event in timeline.events),
        )
        self._wait_for_node(node)
        if any(isinstance(event, SendGoal) for event in timeline.events):
            self._wait_for_the_action_server()
        self._node_uri = self._find_node()
        self._wait_until_the_node_sends_to_us(self._node_uri)
        self._checks = self._health_checks(scenario.config.health_check_period)
        stand_ins.come_up_first()
        if self._options.real_time:
            self._align_with_the_node(scenario.config.health_check_period)
        play(timeline, self, stand_ins, self._schedule.stops)
        # What was observed by the end of the timeline, before anything is torn down: a health
        # check between stopping soundDetection and stopping the node is no part of the scenario.
        outcome, self._outcome = self._outcome, self._new_outcome()
        self._node_uri = None
        self._checks = None
        self._checked_at = -math.inf
        stand_ins.stop(node)
        return outcome


def _filled(word: str, values: Dict[str, str]) -> str:
    for placeholder, value in values.items():
        word = word.replace(placeholder, value)
    return word
