"""An engine in a process of its own (speech_event/recognizers/engine_process.py), on a stand-in
engine that starts fast (fixtures/stub_engine.py): calls, exceptions, a child that dies, and
no process left behind. pocketsphinx hosted so: test_sphinx_process.py."""

import functools
import gc
import os
import signal
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path
from typing import Iterator, List

import pytest

from fixtures.paths import ROOT
from fixtures.processes import children, running
from fixtures.stub_engine import StubEngine
from speech_event.errors import GrammarError, ModelError
from speech_event.recognizers.engine_process import EngineProcess, EngineProcessError


@pytest.fixture
def stub() -> Iterator[EngineProcess]:
    before = children()
    process = EngineProcess("stub", StubEngine, replayed=("use_grammar",))
    yield process
    process.close()
    assert children() == before


def _wait_until_gone(pid: int, seconds: float = 10.0) -> bool:
    deadline = time.monotonic() + seconds
    while running(pid) and time.monotonic() < deadline:
        time.sleep(0.02)
    return not running(pid)


def test_calls_run_in_the_child(stub: EngineProcess) -> None:
    assert stub.call("pid") == stub.pid != os.getpid()
    assert stub.call("echo", {"a": [1, 2]}) == {"a": [1, 2]}
    assert stub.read("sample_rate") == 8000
    assert stub.engine_class == "StubEngine"


@pytest.mark.parametrize(
    "error", [GrammarError("cards.gram: no public rule"), ModelError("no such model"), ValueError("bad")]
)
def test_the_engines_exceptions_are_raised_with_their_type_and_message(
    stub: EngineProcess, error: Exception
) -> None:
    with pytest.raises(type(error)) as raised:
        stub.call("raise_it", error)
    assert type(raised.value) is type(error) and str(raised.value) == str(error)
    assert "in raise_it" in str(raised.value.__cause__)  # the child's traceback
    assert stub.call("echo", 1) == 1  # the engine goes on


def test_an_exception_or_an_answer_that_cannot_cross_the_pipe_fails_only_its_call(
    stub: EngineProcess,
) -> None:
    with pytest.raises(EngineProcessError) as raised:
        stub.call("raise_unpicklable")
    assert str(raised.value) == "Unpicklable: no pickle (7)"
    with pytest.raises(TypeError, match="lock"):
        stub.call("unpicklable_answer")
    with pytest.raises(AttributeError, match="no_such_method"):
        stub.call("no_such_method")
    assert stub.call("echo", 2) == 2


def test_a_factory_that_fails_raises_its_error_and_leaves_no_process() -> None:
    before = children()
    with pytest.raises(ModelError) as raised:
        EngineProcess("stub", functools.partial(StubEngine, "no such model"))
    assert str(raised.value) == "no such model"
    assert children() == before


def test_a_child_that_died_fails_the_call_and_the_next_call_starts_another_with_the_state_set(
    stub: EngineProcess,
) -> None:
    stub.call("use_grammar", "yes|no")
    first = stub.pid
    assert first is not None
    os.kill(first, signal.SIGKILL)
    with pytest.raises(EngineProcessError) as raised:
        stub.call("echo", 1)
    assert (
        str(raised.value)
        == "stub's process ended (exit status -9) while echo; it starts again at the next call"
    )
    assert not running(first)  # waited for: no zombie
    assert stub.read("grammar") == "yes|no"  # use_grammar made again on the new child
    assert stub.pid not in (None, first)


def test_a_child_that_dies_in_the_middle_of_a_call_fails_that_call(stub: EngineProcess) -> None:
    with pytest.raises(EngineProcessError, match=r"^stub's process ended \(exit status 3\) while exit;"):
        stub.call("exit", 3)
    assert stub.call("echo", "again") == "again"


def test_calls_from_several_threads_each_get_their_own_answer(stub: EngineProcess) -> None:
    answers: List[object] = [None] * 8

    def ask(index: int) -> None:
        answers[index] = stub.call("echo", index, 0.01 * (index % 3))

    threads = [threading.Thread(target=ask, args=(index,)) for index in range(len(answers))]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert answers == list(range(len(answers)))


def test_close_ends_the_child_and_later_calls_fail() -> None:
    process = EngineProcess("stub", StubEngine)
    pid = process.pid
    assert pid is not None and running(pid)
    process.close()
    assert not running(pid) and process.pid is None
    with pytest.raises(EngineProcessError, match=r"^stub's process was closed$"):
        process.call("echo", 1)
    process.close()  # twice is harmless


def test_an_engine_dropped_unclosed_ends_its_child() -> None:
    process = EngineProcess("stub", StubEngine)
    pid = process.pid
    assert pid is not None
    del process
    gc.collect()
    assert not running(pid)


def _run(tmp_path: Path, script: str) -> "subprocess.CompletedProcess[str]":
    path = tmp_path / "script.py"
    path.write_text(textwrap.dedent(script))
    environment = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, str(path)], capture_output=True, text=True, timeout=60, env=environment, check=False
    )


def test_the_child_ends_when_its_parent_is_killed(tmp_path: Path) -> None:
    result = _run(
        tmp_path,
        """
        import os, signal
        from speech_event.recognizers.engine_process import EngineProcess
        from fixtures.stub_engine import StubEngine
        process = EngineProcess("stub", StubEngine)
        print(process.pid, flush=True)
        os.kill(os.getpid(), signal.SIGKILL)  # no finalizer runs: only the pipe's end tells the child
        """,
    )
    assert result.returncode == -signal.SIGKILL
    assert _wait_until_gone(int(result.stdout))


def test_a_script_without_a_main_guard_hosts_an_engine(tmp_path: Path) -> None:
    """multiprocessing's spawn would run this script again in the child, which would start a child
    of its own before its bootstrapping ended: RuntimeError, and no engine."""
    result = _run(
        tmp_path,
        """
        from speech_event.recognizers.engine_process import EngineProcess
        from fixtures.stub_engine import StubEngine
        print(EngineProcess("stub", StubEngine).call("echo", "hosted"))
        """,
    )
    assert (result.returncode, result.stdout, result.stderr) == (0, "hosted\n", "")
