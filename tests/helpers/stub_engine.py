"""An engine stand-in for tests/recognizers/test_engine_process.py, built in the child process:
state to replay, answers, and each way a call can fail. It imports little, so a child starts fast."""

import os
import threading
import time
from typing import Optional

from speech_event.errors import ModelError


class Unpicklable(Exception):
    """An exception whose __init__ takes two arguments: pickle cannot make it again."""

    def __init__(self, what: str, code: int) -> None:
        super().__init__(f"{what} ({code})")


class StubEngine:
    sample_rate = 8000

    def __init__(self, fail: str = "") -> None:
        if fail:
            raise ModelError(fail)
        self.grammar: Optional[str] = None

    def use_grammar(self, grammar: Optional[str]) -> None:
        self.grammar = grammar

    def pid(self) -> int:
        return os.getpid()

    def echo(self, value: object, seconds: float = 0.0) -> object:
        time.sleep(seconds)
        return value

    def raise_it(self, error: Exception) -> None:
        raise error

    def raise_unpicklable(self) -> None:
        raise Unpicklable("no pickle", 7)

    def unpicklable_answer(self) -> object:
        return threading.Lock()

    def exit(self, status: int) -> None:
        os._exit(status)
