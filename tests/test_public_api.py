"""What a program embedding the node imports from ``speech_event`` itself is enough to run it."""

from typing import List

import speech_event
from fixtures.audio import speak_tones


def test_the_package_docstrings_recipe_runs_the_node_with_public_names_only() -> None:
    se = speech_event
    config = se.SpeechEventConfig(sample_rate=16000)
    bus, clock = se.InMemoryBus(), se.FakeClock()
    node = se.SpeechEventNode(config, bus, clock, se.RECOGNIZERS["fake"](config), se.ClockExecutor(clock))
    node.start()
    heard: List[str] = []
    bus.subscribe(se.TEXT_TOPIC, se.String, lambda message: heard.append(message.data))  # type: ignore[attr-defined]
    sound_detection = bus.advertise(se.SIGNAL_TOPIC, se.Float32MultiArray, node="soundDetection")
    speech = speak_tones("yego", 16000)
    for start in range(0, speech.size, 4096):
        clock.advance(4096 / 16000)
        sound_detection.publish(se.Float32MultiArray(data=speech[start : start + 4096]))
    clock.advance(config.speech_pause_period + 0.1)
    assert heard == ["yego"]
    node.stop()


def test_every_public_name_is_importable_and_listed_once() -> None:
    names = speech_event.__all__
    assert len(names) == len(set(names))
    assert all(hasattr(speech_event, name) for name in names)
    assert {"SpeechEventNode", "SpeechEventConfig", "load_config", "Transport", "Clock", "Recognizer"} <= set(
        names
    )
    assert {"Executor", "InMemoryBus", "FakeClock", "SystemClock", "ClockExecutor", "ThreadExecutor"} <= set(
        names
    )
    assert {"RECOGNIZERS", "Float32MultiArray", "String", "Stoppable", "WholePhrases"} <= set(names)
    assert isinstance(
        speech_event.RECOGNIZERS["fake"](speech_event.SpeechEventConfig()), speech_event.Stoppable
    )
