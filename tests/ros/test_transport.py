"""RosTransport and RosClock against a real roscore."""

import os
import signal
import subprocess
import sys
import threading
import time
from typing import Dict, List

import numpy as np
import rosgraph

from fixtures.paths import ROOT
from fixtures.ros import wait_for
from speech_event import SIGNAL_TOPIC
from speech_event.adapters.ros import RosClock, RosTransport, _to_ros, transcript_from_ros
from speech_event.messages import Float32MultiArray, String, TranscriptMessage
from speech_event.ports import PublisherStatus

STAND_IN = [
    sys.executable,
    str(ROOT / "scripts" / "sound_detection_replay.py"),
    str(ROOT / "scenarios" / "single_utterance.toml"),
]


def test_audio_and_text_round_trip_exactly(roscore: Dict[str, str]) -> None:
    transport = RosTransport()
    audio: List[object] = []
    texts: List[object] = []
    transport.subscribe("/test/audio", Float32MultiArray, audio.append)
    transport.subscribe("/test/text", String, texts.append)
    audio_out = transport.advertise("/test/audio", Float32MultiArray)
    text_out = transport.advertise("/test/text", String)
    wait_for(lambda: audio_out.connections() > 0 and text_out.connections() > 0, "the connections")
    block = np.random.default_rng(0).uniform(-1, 1, 4096).astype(np.float32)
    audio_out.publish(Float32MultiArray(data=block))
    text_out.publish(String("go to the kitchen"))
    wait_for(lambda: audio and texts, "both messages")
    received = audio[0]
    assert received._type == "std_msgs/Float32MultiArray"  # type: ignore[attr-defined]
    assert received.data.dtype == np.float32  # type: ignore[attr-defined]
    assert np.array_equal(received.data, block)  # type: ignore[attr-defined]
    assert list(received.layout.dim) == []  # type: ignore[attr-defined]
    assert texts[0].data == "go to the kitchen"  # type: ignore[attr-defined]


def _start_stand_in(environment: Dict[str, str]) -> "subprocess.Popen[str]":
    process = subprocess.Popen(
        STAND_IN,
        env=environment,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    assert process.stdout is not None and process.stdin is not None
    assert process.stdout.readline().strip() == "started"  # a ROS node, not yet a publisher
    process.stdin.write("advertise\n")
    process.stdin.flush()
    assert process.stdout.readline().strip() == "ready"
    return process


def test_a_sigkilled_publisher_reads_as_stale_then_a_restart_connects_and_a_clean_exit_unregisters(
    roscore: Dict[str, str],
) -> None:
    transport = RosTransport()
    transport.subscribe(SIGNAL_TOPIC, Float32MultiArray, lambda message: None)
    assert transport.publisher_status(SIGNAL_TOPIC) is PublisherStatus.NONE
    first = _start_stand_in(roscore)
    wait_for(lambda: transport.publisher_status(SIGNAL_TOPIC) is PublisherStatus.CONNECTED, "connected")
    os.killpg(first.pid, signal.SIGKILL)
    first.wait()
    wait_for(lambda: transport.publisher_status(SIGNAL_TOPIC) is PublisherStatus.STALE, "stale")
    master = rosgraph.Master("/speechEventTests")
    publishers = {topic: nodes for topic, nodes in master.getSystemState()[0]}
    assert publishers[SIGNAL_TOPIC] == ["/soundDetection"]  # the killed node is still registered
    second = _start_stand_in(roscore)
    wait_for(lambda: transport.publisher_status(SIGNAL_TOPIC) is PublisherStatus.CONNECTED, "reconnected")
    assert second.stdin is not None
    second.stdin.write("shutdown\n")
    second.stdin.flush()
    assert second.wait(20) == 0
    wait_for(lambda: transport.publisher_status(SIGNAL_TOPIC) is PublisherStatus.NONE, "unregistered")


def test_the_ros_clock_runs_timers_on_ros_time_and_cancels_them(roscore: Dict[str, str]) -> None:
    clock = RosClock()
    fired = threading.Event()
    cancelled = threading.Event()
    start = clock.now()
    clock.call_at(start + 0.2, fired.set)
    clock.call_at(start + 0.1, cancelled.set).cancel()
    assert fired.wait(5)
    assert clock.now() >= start + 0.2 - 1e-3
    time.sleep(0.2)
    assert not cancelled.is_set()


def test_a_block_is_stamped_when_read_and_a_timer_due_after_it_waits_for_its_callback(
    roscore: Dict[str, str],
) -> None:
    """rospy counts a message as received before it calls back: a sim-time replay moves the clock
    on from that count, so the node's arrival time and its timers must not depend on when the
    callback runs (it may wait for the node's lock)."""
    transport, clock = RosTransport(), RosClock()
    entered, release = threading.Event(), threading.Event()
    order: List[str] = []
    stamps: List[float] = []

    def slow_callback(message: object) -> None:
        stamps.append(message.received_at)  # type: ignore[attr-defined]
        entered.set()
        release.wait(30)
        order.append("block taken")

    transport.subscribe("/test/in_flight", Float32MultiArray, slow_callback)
    audio_out = transport.advertise("/test/in_flight", Float32MultiArray)
    wait_for(lambda: audio_out.connections() > 0, "the connection")
    sent_at = clock.now()
    audio_out.publish(Float32MultiArray(data=np.zeros(4096, np.float32)))
    assert entered.wait(30)
    called_back_at = clock.now()
    timer_done = threading.Event()

    def timer() -> None:
        order.append("timer")
        timer_done.set()

    clock.call_at(clock.now(), timer)  # due now, after the block was read
    time.sleep(0.3)  # long enough for a timer that does not wait to run; a waiting one waits on
    release.set()
    assert timer_done.wait(30)
    assert order == ["block taken", "timer"]
    assert sent_at <= stamps[0] <= called_back_at


def test_every_script_names_the_system_python_so_a_pyenv_python3_cannot_break_rospy() -> None:
    for script in sorted((ROOT / "scripts").iterdir()):
        assert script.read_text().startswith("#!/usr/bin/python3\n"), script
        assert os.access(script, os.X_OK), script


def test_a_transcript_message_crosses_to_ros_and_back_field_by_field() -> None:
    message = TranscriptMessage(
        12.5, "go to the kitchen", True, 0.75, "kinyarwanda", "NemoRecognizer", 10.25, 11.5
    )
    ros = _to_ros(message)
    assert type(ros).__name__ == "Transcript" and ros.header.stamp.to_sec() == 12.5  # type: ignore[attr-defined]
    assert transcript_from_ros(ros) == message
