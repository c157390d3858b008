"""An engine in a process of its own, so that the node's own threads never wait for it.

pocketsphinx's Cython binding holds the GIL for a whole ``process_raw``: 7 s of speech held it
1.7 s. Meanwhile the node's subscriber callback, which stamps each block's arrival, and its timers
stood still, so blocks came in late and in a burst, and where an utterance ended (a gap in arrival
times, ``speech_pause_period``) depended on how fast the one before was decoded (issue 30). Hosted
here, the engine decodes in a child process; the node's worker thread waits on a pipe, which
releases the GIL.

The child is a new interpreter: never a bare fork, since the node has threads and a fork copies
the locks they hold; and not multiprocessing's spawn, which runs the parent's main script again in
the child (an embedding script without ``if __name__ == "__main__"`` would fail, or start children
without end). It takes the parent's sys.path, so it imports the same code, builds its engine with
a picklable factory and answers one call at a time. One lock makes each call one exchange on the
pipe, so a service thread's ``check_grammar`` never interleaves with the worker's ``transcribe``.
The engine's exceptions are raised in the parent with their type and message (the child's
traceback as their cause). A child that died fails the call that found it with EngineProcessError;
the next call starts a new one, on which the calls that set state (``replayed``) are made again.
The child ends when its pipe closes: ``close()``, the parent's exit (a finalizer closes it) or its
death.
"""

import multiprocessing
import os
import pickle
import subprocess
import sys
import threading
import traceback
import weakref
from multiprocessing.connection import Connection
from typing import Any, Callable, Dict, Optional, Tuple

# Builds the engine in the child: picklable (a module-level function or class, a functools.partial).
EngineFactory = Callable[[], object]
# A method's name and its arguments; no arguments (None): the value of the attribute of that name.
_Request = Tuple[str, Optional[Tuple[Any, ...]]]
# (True, the value) or (False, the exception, the child's traceback).
_Reply = Tuple[Any, ...]
# How long a closing child has to end by itself (it is between calls: it only has to exit).
_CLOSE_GRACE_SECONDS = 5.0
# The child's program, given its end of the pipe. Ctrl-C reaches the whole process group, but the
# parent decides when the child ends (it closes the pipe). The parent's sys.path comes first: the
# factory is unpickled, so its module imported, only with it.
_BOOTSTRAP = (
    "import signal, sys; signal.signal(signal.SIGINT, signal.SIG_IGN); "
    "from multiprocessing.connection import Connection; connection = Connection(int(sys.argv[1])); "
    "sys.path[:] = connection.recv(); "
    "from speech_event.recognizers.engine_process import serve; serve(connection)"
)


class EngineProcessError(RuntimeError):
    """The engine's process ended or was closed: the call that met it did not run."""


class _ChildTraceback(Exception):
    """The traceback of an exception raised in the child, as its cause: the parent's traceback
    alone would end at the pipe."""

    def __str__(self) -> str:
        return str(self.args[0])


class _Child:
    """One child process and the parent's end of its pipe."""

    def __init__(self) -> None:
        self.connection, child_end = multiprocessing.Pipe()
        fd = child_end.fileno()
        self.process = subprocess.Popen(
            [sys.executable, "-c", _BOOTSTRAP, str(fd)], pass_fds=(fd,), stdin=subprocess.DEVNULL
        )
        # Only the child holds its end now: when it dies, the parent reads EOF instead of waiting.
        child_end.close()

    def end(self) -> None:
        """Close the pipe (the child reads EOF and exits), and make sure it did."""
        self.connection.close()
        try:
            self.process.wait(_CLOSE_GRACE_SECONDS)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


class EngineProcess:
    """An engine built by ``factory`` in a child process, called by method name."""

    def __init__(self, name: str, factory: EngineFactory, replayed: Tuple[str, ...] = ()) -> None:
        """Starts the child and builds the engine there: the factory's exception (a ModelError)
        is raised here. ``name`` names the engine in errors; ``replayed``: the methods whose last
        call is made again on a new child."""
        self._name = name
        self._factory = pickle.dumps(factory)  # a factory that cannot be pickled fails here, at once
        self._replayed = replayed
        self._calls: Dict[str, Tuple[Any, ...]] = {}  # the last call of each replayed method
        self._lock = threading.Lock()
        self._child: Optional[_Child] = None
        self._finalizer: Optional[weakref.finalize[[], EngineProcess]] = None
        self._closed = False
        self.engine_class = ""  # the class name of the engine built (the child's answer to the start)
        with self._lock:
            self._start()

    @property
    def pid(self) -> Optional[int]:
        """The child's process id; None when none runs. Read without the lock, so that a test can
        end the child in the middle of a call."""
        child = self._child
        return None if child is None else child.process.pid

    def call(self, method: str, *args: Any) -> Any:
        """The engine's ``method(*args)``, run in the child."""
        with self._lock:
            value = self._ask((method, args))
            if method in self._replayed:
                self._calls[method] = args
            return value

    def read(self, attribute: str) -> Any:
        """The value of the engine's ``attribute``."""
        with self._lock:
            return self._ask((attribute, None))

    def close(self) -> None:
        """End the child (after the call in progress, if any); later calls raise EngineProcessError."""
        with self._lock:
            self._closed = True
            self._end()

    def _ask(self, request: _Request) -> Any:
        if self._closed:
            raise EngineProcessError(f"{self._name}'s process was closed")
        if self._child is None:
            self._start()
            for method, args in self._calls.items():
                self._exchange((method, args))
        return self._exchange(request)

    def _start(self) -> None:
        child = _Child()
        self._child = child
        self._finalizer = weakref.finalize(self, child.end)  # an engine dropped unclosed ends its child
        self.engine_class = self._exchange(None)  # or the factory's exception

    def _exchange(self, request: Optional[_Request]) -> Any:
        """What the child answers to ``request``; None: to the start (sys.path, the factory)."""
        child = self._child
        assert child is not None
        try:
            if request is None:
                child.connection.send(sys.path)
                child.connection.send_bytes(self._factory)
            else:
                child.connection.send(request)
            reply: _Reply = child.connection.recv()
        except (EOFError, OSError):
            self._end()
            doing = "starting" if request is None else request[0]
            raise EngineProcessError(
                f"{self._name}'s process ended (exit status {child.process.returncode}) while "
                f"{doing}; it starts again at the next call"
            ) from None
        except BaseException:
            # Interrupted between sending and reading (KeyboardInterrupt): the reply would answer the
            # next call, so this child is given up.
            self._end()
            raise
        if reply[0]:
            return reply[1]
        if request is None:  # the engine could not be built: no child to keep
            self._end()
        error: BaseException = reply[1]
        raise error from _ChildTraceback(reply[2])

    def _end(self) -> None:
        if self._finalizer is not None:
            self._finalizer()  # child.end, once
        self._child, self._finalizer = None, None


def serve(connection: Connection) -> None:
    """The child, once it has the parent's sys.path (_BOOTSTRAP): build the engine, then answer
    requests until the parent's end closes."""
    try:
        try:
            engine = pickle.loads(connection.recv_bytes())()
        except (Exception, SystemExit) as error:
            connection.send(_failure(error))
            return
        connection.send((True, type(engine).__name__))
        while True:
            reply = _answer(engine, connection.recv())
            try:
                connection.send(reply)
            except (pickle.PicklingError, TypeError, AttributeError) as error:  # nothing was sent
                connection.send(_failure(error))
    except (EOFError, OSError):  # the parent closed its end, or is gone
        pass
    # Nothing to clean up: the engine's memory goes with the process. Tearing the interpreter and
    # pocketsphinx's decoders down took 0.1 s, which each close() waited for.
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)


def _answer(engine: object, request: _Request) -> _Reply:
    name, args = request
    try:
        value = getattr(engine, name)
        return (True, value if args is None else value(*args))
    except (Exception, SystemExit) as error:
        return _failure(error)


def _failure(error: BaseException) -> _Reply:
    """``error`` as the parent will raise it: itself when it survives pickling, else an
    EngineProcessError with its type and message."""
    text = "".join(traceback.format_exception(type(error), error, error.__traceback__))
    try:
        pickle.loads(pickle.dumps(error))  # an exception whose __init__ takes other arguments fails here
    except Exception:
        error = EngineProcessError(f"{type(error).__name__}: {error}")
    return (False, error, text)
