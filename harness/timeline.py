"""Turns a scenario's steps into what soundDetection does, and when, on the scenario clock.

Both transports play the same timeline, so a scenario means the same thing in memory and on ROS.
soundDetection publishes 4096-sample blocks, each when it has been recorded (paced in real time);
it is up at t = 0 and stays up and silent after the last step until the node's pause has passed
(and every action goal's wait). Service calls and action goals take no scenario time; one that
waits for a text (``after_text``) is made at its time in memory, where the text must have come by
then, and later on a real clock if the text comes later (harness/player.py).
"""

from dataclasses import dataclass
from typing import List, Union

import numpy as np

from fixtures.audio import noise
from fixtures.malformed import BLOCK_SAMPLES, malformed_message
from fixtures.noises import AudioFileError, at_level, read_audio, under
from harness.catalog import VOICES, Voice
from harness.scenario import (
    Enable,
    Language,
    Listen,
    Malformed,
    Noise,
    Outage,
    Play,
    Say,
    Scenario,
    ScenarioError,
    SetGrammar,
    Silence,
)
from speech_event.interfaces.services import SET_ENABLED_SERVICE, SET_GRAMMAR_SERVICE, SET_LANGUAGE_SERVICE
from speech_event.messages import (
    Float32MultiArray,
    RecogniseSpeechGoal,
    SetEnabledRequest,
    SetGrammarRequest,
    SetLanguageRequest,
)

# After the last step the clock runs on for the pause period plus this, so the last utterance closes.
SETTLE_SECONDS = 0.5


@dataclass(frozen=True)
class Publish:
    time: float
    message: object


@dataclass(frozen=True)
class GoDown:
    time: float
    kind: str  # "shutdown" or "crash"


@dataclass(frozen=True)
class ComeUp:
    time: float


@dataclass(frozen=True)
class CallService:
    time: float
    service: str  # SET_ENABLED_SERVICE, SET_LANGUAGE_SERVICE or SET_GRAMMAR_SERVICE
    request: object
    after_text: bool = False  # made once the text of the utterance before it has come


@dataclass(frozen=True)
class SendGoal:
    time: float
    goal: RecogniseSpeechGoal
    after_text: bool = False


Event = Union[Publish, GoDown, ComeUp, CallService, SendGoal]


@dataclass(frozen=True)
class Timeline:
    events: List[Event]
    end: float


def _blocks(audio: np.ndarray, start: float, sample_rate: int) -> List[Publish]:
    count = -(-audio.size // BLOCK_SAMPLES)
    padded = np.zeros(count * BLOCK_SAMPLES, dtype=np.float32)
    padded[: audio.size] = audio
    block_seconds = BLOCK_SAMPLES / sample_rate
    return [
        Publish(start + (index + 1) * block_seconds, Float32MultiArray(data=block))
        for index, block in enumerate(padded.reshape(count, BLOCK_SAMPLES))
    ]


def _audio(step: Union[Say, Play, Noise], voice: Voice, rate: int, rng: np.random.Generator) -> np.ndarray:
    """What soundDetection hears for a step that makes sound, at ``rate``."""
    try:
        if isinstance(step, Noise):
            if step.kind == "white":  # the samples every scenario had before the other kinds
                return noise(round(step.seconds * rate), step.level_db, rng)
            return at_level(step.kind, round(step.seconds * rate), step.level_db, rate, rng)
        if isinstance(step, Say):
            speech = voice.speak(step.text, rate)
        else:
            gain = np.float32(10.0 ** (step.gain_db / 20.0))
            speech = np.clip(read_audio(step.path, rate) * gain, -1.0, 1.0)
        return speech if step.noise is None else under(speech, step.noise.kind, step.noise.snr_db, rate, rng)
    except AudioFileError as problem:
        raise ScenarioError(str(problem)) from None


def build_timeline(scenario: Scenario) -> Timeline:
    config = scenario.config
    rate = config.sample_rate
    rng = np.random.default_rng(scenario.seed)
    voice = VOICES[scenario.voice]
    events: List[Event] = []
    time = 0.0
    last_deadline = 0.0  # when the last action goal stops waiting for speech
    for step in scenario.steps:
        if isinstance(step, (Say, Play, Noise)):
            audio = _audio(step, voice, rate, rng)
            blocks = _blocks(audio, time, rate)
            if scenario.background_noise_db is not None:
                for block in blocks:
                    data = block.message.data  # type: ignore[attr-defined]
                    data += noise(data.size, scenario.background_noise_db, rng)
                    np.clip(data, -1.0, 1.0, out=data)
            events.extend(blocks)
            time += len(blocks) * BLOCK_SAMPLES / rate
        elif isinstance(step, Silence):
            time += step.seconds
        elif isinstance(step, Malformed):
            events.append(Publish(time, malformed_message(step.kind, rate, config.max_message_length, rng)))
        elif isinstance(step, Outage):
            events.append(GoDown(time, step.kind))
            time += step.seconds
            events.append(ComeUp(time))
        elif isinstance(step, Enable):
            request: object = SetEnabledRequest(step.request)
            events.append(CallService(time, SET_ENABLED_SERVICE, request, step.after_text))
        elif isinstance(step, Language):
            request = SetLanguageRequest(step.request)
            events.append(CallService(time, SET_LANGUAGE_SERVICE, request, step.after_text))
        elif isinstance(step, SetGrammar):
            request = SetGrammarRequest(step.request)
            events.append(CallService(time, SET_GRAMMAR_SERVICE, request, step.after_text))
        elif isinstance(step, Listen):
            events.append(SendGoal(time, RecogniseSpeechGoal(step.wait), step.after_text))
            last_deadline = max(last_deadline, time + step.wait)
    end = max(time + config.speech_pause_period, last_deadline) + SETTLE_SECONDS
    return Timeline(events, end)
