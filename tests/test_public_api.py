"""What a program embedding the node imports from ``speech_event`` itself is enough to run it."""

import ast
import subprocess
import sys
from typing import List

import speech_event
from fixtures.audio import speak_tones
from fixtures.paths import ROOT


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
    assert {"RECOGNIZERS", "Float32MultiArray", "String", "Stoppable", "Grammars", "Grammar"} <= set(names)
    assert isinstance(
        speech_event.RECOGNIZERS["fake"](speech_event.SpeechEventConfig()), speech_event.Stoppable
    )


def test_importing_the_package_imports_no_numpy_so_ros_tools_under_the_system_python_load_its_types() -> None:
    # rosservice and rostopic import speech_event.srv / .msg under /usr/bin/python3, which may have
    # no numpy: the package itself must import nothing heavy until a name is used.
    code = "import sys, speech_event; print(sorted(m for m in ('numpy', 'speech_event.node') if m in sys.modules))"
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True
    )
    assert result.stdout == "[]\n"


def test_the_imports_for_type_checkers_name_exactly_the_public_names_each_from_its_module() -> None:
    """The package lists its public names once, in the lazy map that ``__all__`` is computed from;
    type checkers read its TYPE_CHECKING imports instead, which must name the same, each
    re-exported as itself."""
    tree = ast.parse((ROOT / "speech_event" / "__init__.py").read_text(encoding="utf-8"))
    (block,) = [
        node
        for node in tree.body
        if isinstance(node, ast.If) and isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING"
    ]
    assert all(isinstance(statement, ast.ImportFrom) for statement in block.body)
    imported = [
        (statement.module, alias.name, alias.asname)
        for statement in block.body
        if isinstance(statement, ast.ImportFrom)
        for alias in statement.names
    ]
    assert sorted(imported) == sorted((module, name, name) for name, module in speech_event._EXPORTS.items())
    assert speech_event.__all__ == sorted(speech_event._EXPORTS)
