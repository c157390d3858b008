"""The one walk over a timeline (harness/player.py), and the node's own times the in-memory run notes
for the ROS replay's schedule (harness/schedule.py), and what a replay waits for there."""

from typing import List

from fixtures.paths import ROOT
from harness.memory_runner import run_in_memory
from harness.outcome import SIM_TIME, Outcome, Published
from harness.player import play
from harness.report import passed, report
from harness.scenario import Say, Scenario, Silence, load_scenario
from harness.schedule import Due, HealthChecks, Schedule
from harness.timeline import CallService, ComeUp, GoDown, Publish, SendGoal, Timeline, build_timeline
from speech_event.config import SpeechEventConfig, speculation_gap_seconds
from speech_event.interfaces.services import SET_ENABLED_SERVICE
from speech_event.messages import Float32MultiArray, RecogniseSpeechGoal, SetEnabledRequest, String
from speech_event.topics import SOUND_DETECTION_DOWN as DOWN


class _Recorder:
    """Both sides of a runner, writing down what the walk asks of them."""

    def __init__(self) -> None:
        self.log: List[str] = []

    def advance_to(self, when: float) -> None:
        self.log.append(f"clock {when}")

    def settle(self, played: int, final: bool) -> None:
        self.log.append(f"settle {played}{' final' if final else ''}")

    def publish(self, index: int, message: Float32MultiArray) -> None:
        self.log.append(f"publish {index}")

    def intrude(self, index: int, message: object) -> None:
        self.log.append(f"intrude {index}")

    def go_down(self, crash: bool) -> None:
        self.log.append(f"down crash={crash}")

    def come_up(self) -> None:
        self.log.append("up")

    def call(self, service: str, request: object) -> None:
        self.log.append(f"call {service}")

    def send_goal(self, goal: RecogniseSpeechGoal) -> None:
        self.log.append("goal")

    def wait_for_text(self, played: int) -> None:
        self.log.append(f"wait for text {played}")


def test_the_walk_stops_at_every_event_time_stop_and_the_end_and_settles_around_each_event() -> None:
    timeline = Timeline(
        [
            Publish(0.5, Float32MultiArray(data=[0.0])),
            Publish(0.5, String(data="not audio")),
            GoDown(1.0, "crash"),
            ComeUp(2.0),
            CallService(2.0, SET_ENABLED_SERVICE, SetEnabledRequest("false")),
            SendGoal(3.0, RecogniseSpeechGoal(1.0)),
        ],
        end=4.0,
    )
    recorder = _Recorder()
    play(timeline, recorder, recorder, stops=[1.5, 0.5])
    assert recorder.log == [
        "clock 0.5",
        "settle 0",
        "publish 0",
        "settle 1",
        "intrude 1",
        "settle 2",
        "clock 1.0",
        "settle 2",
        "down crash=True",
        "settle 3",
        "clock 1.5",
        "settle 3",
        "clock 2.0",
        "settle 3",
        "up",
        "settle 4",
        f"call {SET_ENABLED_SERVICE}",
        "settle 5",
        "clock 3.0",
        "settle 5",
        "goal",
        "settle 6",
        "clock 4.0",
        "settle 6 final",
    ]


def test_a_call_or_goal_that_waits_for_a_text_waits_after_settling_and_before_it_is_made() -> None:
    timeline = Timeline(
        [
            Publish(0.5, Float32MultiArray(data=[0.0])),
            CallService(2.0, SET_ENABLED_SERVICE, SetEnabledRequest("false"), after_text=True),
            SendGoal(2.0, RecogniseSpeechGoal(1.0), after_text=True),
            SendGoal(2.0, RecogniseSpeechGoal(1.0)),
        ],
        end=3.0,
    )
    recorder = _Recorder()
    play(timeline, recorder, recorder)
    assert recorder.log[recorder.log.index("clock 2.0") :] == [
        "clock 2.0",
        "settle 1",
        "wait for text 1",
        f"call {SET_ENABLED_SERVICE}",
        "settle 2",
        "wait for text 2",
        "goal",
        "settle 3",
        "goal",
        "settle 4",
        "clock 3.0",
        "settle 4 final",
    ]


def test_the_in_memory_run_notes_the_nodes_own_times_its_checks_and_the_utterance_end() -> None:
    config = SpeechEventConfig()
    scenario = Scenario("one", "one", config, (Say("go"), Silence(4.0)), ("go",), voice="tones")
    outcome = run_in_memory(scenario)
    last_block = build_timeline(scenario).events[-1].time
    assert outcome.published[0].time == last_block + config.speech_pause_period
    assert last_block + config.speech_pause_period in outcome.node_timers  # the pause ended it
    assert (
        last_block + speculation_gap_seconds(config, deciding=False) in outcome.node_timers
    )  # the node speculated
    assert config.health_check_period in outcome.node_timers


def test_a_replay_says_what_it_still_waits_for_and_a_failing_report_shows_each_wait_it_gave_up() -> None:
    config = SpeechEventConfig()
    scenario = Scenario("one", "one", config, (Say("go"), Silence(4.0)), ("go",), voice="tones")
    schedule = Schedule.of(scenario)
    end = schedule.rehearsal.published[0].time
    assert schedule.due(end - 0.001, 10**6) == Due(texts=(), results=(), partials=("go",))  # 'go' so far
    due = schedule.due(end, 10**6)
    assert due == Due(texts=("go",), results=(), partials=("go",))
    observed = Outcome(clock=SIM_TIME)
    assert due.missing(observed) == "1 text(s), 1 partial text(s)"
    many = Due(("go", "go"), ("",), ("a", "b", "c"))
    assert many.missing(observed) == "2 text(s), 1 action result(s), 3 partial text(s)"
    observed.gave_up.append(
        "at t=4.500 s, waited 30.0 s for 1 text(s) that the node published by then in memory"
    )
    assert report(scenario, observed).splitlines()[-2:] == [
        "      published, with scenario times:",
        "      gave up: at t=4.500 s, waited 30.0 s for 1 text(s) that the node published by then in memory",
    ]
    observed.published.append(Published(4.6, "go"))
    observed.partials.append(Published(2.5, "go"))
    assert due.missing(observed) == ""


def test_a_result_the_node_gives_in_answer_to_a_goal_is_due_after_that_goal_not_before_it() -> None:
    """The second goal preempts the first: in memory its result comes while the goal is sent. Due
    before that goal, a ROS replay waited its whole text deadline for it (30 s), then went on."""
    scenario = load_scenario(str(ROOT / "scenarios" / "listen_preempted.toml"), SpeechEventConfig())
    schedule = Schedule.of(scenario)
    second_goal = [
        index for index, event in enumerate(build_timeline(scenario).events) if isinstance(event, SendGoal)
    ][1]
    preempted = schedule.rehearsal.results[0]
    assert (preempted.text, preempted.played) == ("preempted: ", second_goal + 1)
    assert schedule.due(preempted.time, second_goal).results == ()  # before it: nothing to wait for
    assert schedule.due(preempted.time, second_goal + 1).results == ("preempted: ",)


def test_a_replay_that_gave_up_waiting_fails_even_where_what_it_waited_for_came_later() -> None:
    scenario = Scenario("one", "one", SpeechEventConfig(), (Say("go"),), ("go",), voice="tones")
    observed = Outcome(published=[Published(2.0, "go")], clock=SIM_TIME)
    assert passed(scenario, observed)
    observed.gave_up.append(
        "at t=1.000 s, waited 30.0 s for 1 text(s) that the node published by then in memory"
    )
    assert not passed(scenario, observed)
    assert report(scenario, observed).startswith("FAIL  one  (one)\n")


def test_a_text_memory_did_not_publish_does_not_stand_in_for_one_still_to_come() -> None:
    # tts_outage_between_commands on a busy roscore: a health check that ran late saw the crash
    # after it and said so; counted, that error stood in for 'open the door' and the replay ended
    # before the node published it
    due = Due(
        texts=("what time is it", "Error: soundDetection is down", "open the door"), results=(), partials=()
    )
    observed = Outcome(clock=SIM_TIME)
    for text in ("Error: soundDetection is down", "what time is it", "Error: soundDetection is down"):
        observed.published.append(Published(2.0, text))
    assert due.missing(observed) == "1 text(s)"
    observed.published.append(Published(7.6, "open the door"))
    assert due.missing(observed) == ""


def test_a_text_published_after_an_error_it_came_before_in_memory_is_no_longer_awaited() -> None:
    # people_digits in real time beside busy processes: 'three' was still being recognized when
    # the check found soundDetection down, and came after the error
    due = Due(texts=("seven", "three", DOWN, DOWN, "two"), results=(), partials=())
    observed = Outcome(clock=SIM_TIME)
    for text in ("seven", DOWN, "three", DOWN, "two"):
        observed.published.append(Published(2.0, text))
    assert due.missing(observed) == ""
    observed.published.pop()
    assert due.missing(observed) == "1 text(s)"


def test_the_health_checks_fall_at_whole_periods_after_the_nodes_start() -> None:
    checks = HealthChecks(started_at=0.0, period=2.0)
    assert [when for when in (0.0, 1.0, 2.0, 2.524, 4.0, 6.0000004, 6.001) if checks.at(when)] == [
        2.0,
        4.0,
        6.0000004,
    ]
    assert HealthChecks(started_at=0.25, period=0.5).at(1.25)
