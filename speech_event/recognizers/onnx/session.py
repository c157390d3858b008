"""onnxruntime sessions for the engines' model files: the execution providers, clear errors for a
missing or unloadable file, and the check of a file's tensor names and ranks."""

import ctypes
import logging
from pathlib import Path
from typing import Callable, Dict, List, Optional, Sequence

import onnxruntime

from speech_event.errors import ModelError

_LOG = logging.getLogger("speech_event")


def _heap_trim() -> Optional[Callable[[int], int]]:
    """glibc's malloc_trim; None on a C library without it."""
    try:
        trim: Callable[[int], int] = ctypes.CDLL("libc.so.6").malloc_trim
    except (OSError, AttributeError):
        return None
    return trim


# Loading a model parses its whole file, and glibc keeps the heap that parsing frees for later:
# the large conformer's int8 model held 288 MiB after loading, 214 once malloc_trim gave that
# heap back to the system (bench/figures/int8.py).
_TRIM_HEAP = _heap_trim()


def providers(cuda: bool) -> List[str]:
    """CUDA when asked for and onnxruntime has it; otherwise the CPU, with a warning if CUDA was asked for."""
    if not cuda:
        return ["CPUExecutionProvider"]
    if "CUDAExecutionProvider" in onnxruntime.get_available_providers():
        return ["CUDAExecutionProvider", "CPUExecutionProvider"]
    _LOG.warning("cuda is true but this onnxruntime has no CUDAExecutionProvider: running on the CPU")
    return ["CPUExecutionProvider"]


def open_session(
    path: Path, execution_providers: List[str], directory_holds: str
) -> onnxruntime.InferenceSession:
    """``directory_holds``: what a model directory of this kind holds, said when the file is missing."""
    if not path.is_file():
        raise ModelError(f"{path.parent}: missing {path.name}; {directory_holds}")
    options = onnxruntime.SessionOptions()
    options.log_severity_level = 3
    # The memory pattern plans one block for a run's buffers from the shapes of the runs before
    # and keeps it; utterances differ in length, so it mostly grows. Without it (the arena still
    # reuses buffers) the large conformer's int8 peaks at about 470 MiB instead of 560 to 620, and
    # its encoder runs as fast (fp32 too); without the arena as well, the encoder took 12 % longer
    # in int8 and 40 % in fp32 (A/B in one process, 2 cores, 10 s of speech).
    options.enable_mem_pattern = False
    # In the arena, the weights' blocks are rounded up as the arena grows (powers of two): the large
    # conformer's fp32 held 852 MiB after loading instead of 587, int8 404 instead of 362, and
    # allocating them outright costs no speed.
    options.add_session_config_entry("session.use_device_allocator_for_initializers", "1")
    try:
        session = onnxruntime.InferenceSession(str(path), options, providers=execution_providers)
    except Exception as problem:  # onnxruntime raises its own exception types
        raise ModelError(f"{path}: onnxruntime cannot load it: {problem}") from None
    if _TRIM_HEAP is not None:
        _TRIM_HEAP(0)
    return session


def last_dimension(session: onnxruntime.InferenceSession, output: str) -> Optional[int]:
    """The size of ``output``'s last dimension when the file fixes it (logits per step), else None."""
    size = next(arg.shape[-1] for arg in session.get_outputs() if arg.name == output)
    return size if isinstance(size, int) else None


class StoppableRuns:
    """The RunOptions of the transcription running now, so that another thread can stop it
    (the node's recognition_timeout and speculative recognition do): its next session run raises."""

    def __init__(self) -> None:
        self._current: Optional[onnxruntime.RunOptions] = None

    def start(self) -> onnxruntime.RunOptions:
        run = onnxruntime.RunOptions()
        self._current = run
        return run

    def stop(self) -> None:
        run = self._current
        if run is not None:
            run.terminate = True


def _describe(expected: Dict[str, int]) -> str:
    return ", ".join(f"{name} ({rank}-D)" if rank > 0 else name for name, rank in expected.items())


def check_tensors(
    path: Path, kind: str, found: Sequence[onnxruntime.NodeArg], expected: Dict[str, int], exporter: str
) -> None:
    """The ``kind`` (inputs or outputs) ``found`` must have the ``expected`` names and ranks (-1: any)."""
    shapes = {arg.name: arg.shape for arg in found}
    missing = [name for name in expected if name not in shapes]
    wrong_rank = [
        f"{name} is {len(shapes[name])}-D"
        for name, rank in expected.items()
        if name in shapes and rank > 0 and len(shapes[name]) != rank
    ]
    if missing or wrong_rank:
        problem = f"missing {', '.join(missing)}" if missing else "; ".join(wrong_rank)
        found_names = f"{path}: {kind} are {sorted(shapes)} ({problem})"
        raise ModelError(f"{found_names}; {path.name} of {exporter} has {_describe(expected)}")
