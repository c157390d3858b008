"""The driver's microphone: any PortAudio input device through sounddevice, as mono blocks at the
driver's sample rate.

Blocks come from PortAudio's callback into a bounded queue and are mixed down, resampled and
handed on on the capturing thread, never in the callback. A missing device, or one that stops
mid-run (unplugged), is said once, with the input devices PortAudio finds, and the driver tries
again every ``retry_period`` with a fresh device list, until it comes back or the driver stops.
"""

import queue
import threading
import time
from typing import Any, Callable, List, Optional, Tuple

import numpy as np
import soxr

from harness.driver import DriverConfig

Say = Callable[[str], None]
# A second of blocks, at most, waits for the capturing thread; past it blocks are dropped (said).
QUEUE_BLOCKS = 64
OVERRUN_REPORT = 10.0


class MicrophoneError(Exception):
    """No usable input device now (the message lists what there is)."""


def load_sounddevice() -> Any:
    """sounddevice, or MicrophoneError saying what to install (it needs the PortAudio library)."""
    try:
        import sounddevice
    except (ImportError, OSError) as problem:  # OSError: the library without libportaudio2
        raise MicrophoneError(
            f"the microphone needs sounddevice and PortAudio (pip install sounddevice; "
            f"apt-get install libportaudio2): {problem}"
        ) from None
    return sounddevice


def input_devices(audio: Any) -> List[Tuple[int, str, int]]:
    """(index, name, input channels) of each input device PortAudio finds."""
    return [
        (int(device["index"]), str(device["name"]), int(device["max_input_channels"]))
        for device in audio.query_devices()
        if device["max_input_channels"] > 0
    ]


def describe_devices(devices: List[Tuple[int, str, int]]) -> str:
    if not devices:
        return "PortAudio finds no input device (is a microphone plugged in?)"
    return "input devices: " + ", ".join(
        f"{index} {name!r} ({channels} ch)" for index, name, channels in devices
    )


def find_device(audio: Any, wanted: str) -> Tuple[int, str, int]:
    """The input device ``wanted`` names (an index, or part of a name; empty: the default)."""
    devices = input_devices(audio)
    if wanted.strip().isdigit():
        matches = [device for device in devices if device[0] == int(wanted)]
    elif wanted:
        matches = [device for device in devices if wanted.lower() in device[1].lower()]
    else:
        default = audio.default.device[0]
        matches = [device for device in devices if device[0] == default] or devices[:1]
    if not matches:
        asked = f"no input device {wanted!r}" if wanted else "no input device"
        raise MicrophoneError(f"{asked}; {describe_devices(devices)}")
    return matches[0]


class Microphone:
    def __init__(
        self, config: DriverConfig, on_audio: Callable[[np.ndarray], None], say: Say, audio: Any
    ) -> None:
        self._config = config
        self._on_audio = on_audio
        self._say = say
        self._audio = audio
        self._last_problem: Optional[str] = None
        self.dropped_blocks = 0  # counted in PortAudio's callback
        self._reported_drops = 0
        self._last_report = float("-inf")

    def run(self, stop: threading.Event) -> None:
        """Capture until ``stop`` is set, trying again after every problem."""
        while not stop.is_set():
            try:
                self._capture(stop)
            except MicrophoneError as problem:
                self._tell(f"{problem}; trying again every {self._config.retry_period:g} s")
            except self._audio.PortAudioError as problem:
                self._tell(
                    f"the input device failed: {problem}; trying again every {self._config.retry_period:g} s"
                )
            if stop.wait(self._config.retry_period):
                return
            # PortAudio lists devices when it starts: start it again to see one plugged in since.
            self._audio._terminate()
            self._audio._initialize()

    def _tell(self, problem: str) -> None:
        if problem != self._last_problem:  # once per problem, not at every retry
            self._say(problem)
        self._last_problem = problem

    def _capture(self, stop: threading.Event) -> None:
        index, name, most = find_device(self._audio, self._config.device)
        channels = min(self._config.channels, most)
        rate = self._rate(index, channels)
        blocks: queue.Queue[np.ndarray] = queue.Queue(QUEUE_BLOCKS)

        def arrived(indata: np.ndarray, frames: int, time: Any, status: Any) -> None:
            # Stopping: end the stream from its own callback. A device that delivers faster than
            # the driver reads (the tests' file device) otherwise keeps PortAudio's thread calling
            # in, and the driver took over 30 s to end after SIGINT (2 CI runs in 5).
            if stop.is_set():
                raise self._audio.CallbackAbort
            try:
                blocks.put_nowait(indata.copy())
            except queue.Full:
                self.dropped_blocks += 1

        resampler = (
            soxr.ResampleStream(rate, self._config.sample_rate, 1, dtype="float32")
            if rate != self._config.sample_rate
            else None
        )
        stream = self._audio.InputStream(
            device=index,
            channels=channels,
            samplerate=rate,
            blocksize=self._config.chunk_size,
            dtype="float32",
            callback=arrived,
        )
        stream.start()
        try:
            self._tell(f"capturing {name!r} (device {index}): {channels} channel(s) at {rate} Hz")
            while not stop.is_set():
                try:
                    block = blocks.get(timeout=0.2)
                except queue.Empty:
                    if not stream.active:
                        raise MicrophoneError(f"the input device {name!r} stopped") from None
                    continue
                self._report_overruns()
                mono = np.ascontiguousarray(block.mean(axis=1), dtype=np.float32)
                if resampler is not None:
                    mono = resampler.resample_chunk(mono)
                if mono.size:
                    self._on_audio(np.clip(mono, -1.0, 1.0))
        finally:
            # Aborted, not stopped: what the device has not handed over yet is of no use, and
            # stopping waits for PortAudio's buffers to drain.
            stream.abort()
            stream.close()

    def _report_overruns(self) -> None:
        """Blocks dropped because this thread fell behind: said at most every OVERRUN_REPORT s."""
        now = time.monotonic()
        if self.dropped_blocks > self._reported_drops and now - self._last_report >= OVERRUN_REPORT:
            self._say(
                f"capture overrun: {self.dropped_blocks} block(s) of {self._config.chunk_size} samples "
                "dropped so far (the driver could not keep up with the device)"
            )
            self._reported_drops, self._last_report = self.dropped_blocks, now

    def _rate(self, index: int, channels: int) -> int:
        """The driver's rate when the device takes it, else the device's own (resampled after)."""
        try:
            self._audio.check_input_settings(
                device=index, channels=channels, dtype="float32", samplerate=self._config.sample_rate
            )
            return self._config.sample_rate
        except Exception:  # sounddevice raises PortAudioError or ValueError for a rate it lacks
            return int(self._audio.query_devices(index)["default_samplerate"])
