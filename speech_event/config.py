"""The node's configuration: the seed's Table 1 keys, the timing keys, and the robot's release keys.

``config/speech_event_configuration.ini`` holds these defaults; see speech_event/keyvalue.py for
the file format and docs/configuration.md for every key. The robot's current release (v1.1) names some keys
its own way (``interUtteranceLen``, ``maxUtteranceLen``): those spellings are aliases here, so its
configuration file loads unchanged.
"""

from dataclasses import dataclass
from pathlib import Path
from typing import Mapping, Optional, Union

from speech_event.errors import ConfigError
from speech_event.keyvalue import (
    KeyRule,
    KeyValueFormat,
    boolean,
    choice,
    file_path,
    number,
    optional,
    seconds,
    text,
)

__all__ = [
    "ConfigError",
    "SpeechEventConfig",
    "apply_overrides",
    "format_config",
    "load_config",
    "parse_config",
]


@dataclass(frozen=True)
class SpeechEventConfig:
    """The node's settings: one field per configuration key, with its default.

    docs/configuration.md describes each key."""

    language: str = "english"
    verbose_mode: bool = False
    rw_model_path: str = ""
    en_model_path: str = ""
    # Empty: utterances are not stored. Otherwise each utterance is written there as a 16 kHz WAV
    # file with a line in index.jsonl (speech_event/pipeline/storage.py), the folder kept under this size.
    audio_storage_dir: str = ""
    audio_storage_max_mb: float = 500.0
    cuda: bool = False
    # int8: run the model's int8 files (speech-event export-nemo/export-whisper --int8, pull --int8).
    quantization: str = "none"
    sample_rate: int = 48000
    speech_pause_period: float = 1.5
    max_utterance_length: float = 10.0
    health_check_period: float = 5.0
    publish_unrecognized: bool = False
    # One message longer than this is rejected whole: no microphone block is anywhere near it.
    max_message_length: float = 60.0
    # Transcripts whose engine-reported confidence is below this count as not recognized.
    confidence: float = 0.0
    # Period of the "still running" info line in verbose mode; 0 turns it off.
    heartbeat_msg_period: float = 10.0
    # A command grammar for every engine (speech_event/grammar.py: a JSGF file or a file of
    # phrases; empty: free speech). Its earlier name pocketsphinx_grammar is an alias.
    grammar: str = ""
    # How much less likely than the engine's own free decoding of the same audio a phrase may be
    # (log-probabilities, in nats; None: the engine's measured default). pocketsphinx publishes its
    # grammar's best path only within it. NeMo and Whisper publish the phrase the free text is,
    # or a phrase it is a mishearing of within it; Whisper also weighs the audio's evidence for a
    # phrase against its score with nothing said, which may take a phrase the words did not
    # (onnx/grammar_choice.py, docs/grammar.md).
    grammar_threshold: Optional[float] = None
    # pocketsphinx only: a keyword list instead of a grammar or its language model.
    pocketsphinx_keywords: str = ""
    # The robot's model family for the NeMo-format engines (rw_model_path, en_model_path).
    model: str = "conformer-transducer"
    # Utterances shorter than this are not transcribed (not speech: a cough, a door).
    min_utterance_length: float = 0.0
    # Silero VAD: an utterance whose highest speech probability stays below this is not
    # transcribed; 0 turns the check off.
    vad_threshold: float = 0.0
    # Seconds of speech that may wait for recognition; past it the oldest utterance is dropped.
    max_backlog: float = 120.0
    # A recognition running longer is logged, and cancelled where the engine allows; 0: never.
    recognition_timeout: float = 30.0
    # Transcribe the utterance so far once no block came for speculation_gap, so its text is
    # ready when the pause ends (speech_event/turns/speculation.py); texts are the same either way.
    speculative_recognition: bool = True
    # None: 0.1 s while the end of speech decides, else 0.3 (speculation_gap_seconds).
    speculation_gap: Optional[float] = None
    # Opt-in early end of turn: publish a complete answer this long after the last block instead
    # of the whole pause; 0: off. Complete: a grammar's phrase, one of complete_answers, or a
    # text two speculations in a row agreed on.
    early_pause: float = 0.0
    complete_answers: str = "yes,no,yego,oya"
    # End of turn at the end of speech (speech_event/turns/end_of_turn.py): once this long of non-speech
    # follows the speech in the audio (or no block came for this long), the turn ends there if
    # the text up to there is complete; 0: off. It decides by speculating: off without
    # speculative_recognition, and early_pause (the older opt-in) takes its place when set.
    # None: on (0.3 s) in grammar mode with Whisper and NeMo, off in free speech and with
    # pocketsphinx (end_of_speech_seconds).
    end_of_speech: Optional[float] = None
    # While an utterance is spoken, publish its text so far on /speechEvent/partial at most this
    # often, when the worker is idle (speech_event/turns/partials.py); 0: off. Final texts are the same.
    partial_period: float = 0.5
    # How free speech's texts are written on /speechEvent/text, the action's result and
    # /speechEvent/partial: robot (lower case, no punctuation, numbers in words, as the robot's NeMo
    # model writes, which its Behaviour Controller's case-sensitive search for "yes" needs) or
    # engine (as the engine writes: Whisper's " Yes."). A grammar's phrases are published as it
    # spells them; /speechEvent/transcript carries the engine's writing either way.
    text_style: str = "robot"
    # In free speech, what else the turn's end needs besides a complete text: none, or smart-turn
    # (Smart Turn v3.2 hears in the audio that the turn is complete; speech_event/turns/
    # smart_turn.py, from the pipecat-ai wheel). With smart-turn the turn ends at the end of speech
    # in free speech too (end_of_speech, 0.3 s where it is not set), when both say it is complete;
    # one of complete_answers ends it at once. auto: smart-turn where its figures were measured
    # (docs/benchmarks.md), in English with an engine that closes sentences (Whisper), if the model
    # is installed; elsewhere none.
    turn_end_model: str = "auto"
    # With turn_end_model: whether the text must be complete too (false: the audio alone decides,
    # as pipecat uses Smart Turn; any text then ends the turn where the model hears it complete).
    turn_end_text: bool = True


MODEL_FAMILIES = ("conformer-transducer", "parakeet", "whisper")
TEXT_STYLES = ("robot", "engine")
TURN_END_MODELS = ("auto", "none", "smart-turn")
QUANTIZATIONS = ("none", "int8")
# Partial results more often than this would only keep the worker busy: no one reads that fast.
SHORTEST_PARTIAL_PERIOD = 0.1


# soundDetection's block: 4096 samples (85 ms at 48 kHz); blocks of one utterance come this far apart.
SOUND_DETECTION_BLOCK = 4096
# end_of_speech where it is not set, for grammar mode: a turn ends there only on a phrase of the
# grammar, and 0.3 s met the targets behind the robot's gate (docs/benchmarks.md).
GRAMMAR_END_OF_SPEECH = 0.3
# speculation_gap where it is not set: speculating 0.1 s after the last block has the text ready
# when the end of speech is heard (0.39 s behind the gate against 0.60 s at 0.3); where the end of
# speech does not decide, 0.3 s spares the worker about 15 speculations a minute that are stopped.
DECIDING_SPECULATION_GAP = 0.1
SPECULATION_GAP = 0.3


def end_of_speech_seconds(config: SpeechEventConfig) -> float:
    """end_of_speech as set, or where it is not, GRAMMAR_END_OF_SPEECH if one block is shorter
    (at 8 kHz a block is 0.51 s: the gaps between blocks would be heard as ends), else 0 (off).
    Left to this default it decides only while a grammar is in force (one may be set at run time:
    set_grammar), with an engine that can be stopped (speculation.decides_at_end_of_speech)."""
    if config.end_of_speech is not None:
        return config.end_of_speech
    block = SOUND_DETECTION_BLOCK / config.sample_rate
    fits = block < GRAMMAR_END_OF_SPEECH < config.speech_pause_period
    return GRAMMAR_END_OF_SPEECH if fits else 0.0


def end_of_speech_chosen(config: SpeechEventConfig) -> bool:
    """Whether end_of_speech is set, not left to its default: then it may end a turn in free
    speech too, and with pocketsphinx (speculation.decides_at_end_of_speech)."""
    return config.end_of_speech is not None


def ends_at_end_of_speech(config: SpeechEventConfig) -> bool:
    """Whether the turn ends at the end of speech (end_of_speech, with what it needs)."""
    return end_of_speech_seconds(config) > 0 and config.speculative_recognition and not config.early_pause


def speculation_gap_seconds(config: SpeechEventConfig, deciding: bool) -> float:
    """speculation_gap as set, or where it is not, DECIDING_SPECULATION_GAP while the end of speech
    decides (``deciding``: with the engine and grammar in force, speculation.decides_at_end_of_speech),
    else SPECULATION_GAP."""
    if config.speculation_gap is not None:
        return config.speculation_gap
    return DECIDING_SPECULATION_GAP if deciding and ends_at_end_of_speech(config) else SPECULATION_GAP


def _together(config: SpeechEventConfig) -> Optional[str]:
    """What is wrong with values that are each allowed but do not work together."""
    block = SOUND_DETECTION_BLOCK / config.sample_rate
    one_block = (
        f"one {SOUND_DETECTION_BLOCK}-sample block at sample_rate {config.sample_rate} Hz ({block:.3f} s)"
    )
    if config.max_message_length < block:
        return (
            f"max_message_length {config.max_message_length} s is shorter than {one_block}: "
            "every block would be rejected"
        )
    if config.speech_pause_period <= block:
        return (
            f"speech_pause_period {config.speech_pause_period} s is not longer than {one_block}: "
            "speech would be cut between blocks"
        )
    gap = speculation_gap_seconds(config, deciding=False)  # early_pause turns the end of speech off
    if config.early_pause and not (
        config.speculative_recognition and gap <= config.early_pause < config.speech_pause_period
    ):
        return (
            f"early_pause {config.early_pause} s needs speculative_recognition true and must be from "
            f"speculation_gap ({gap} s) to less than speech_pause_period "
            f"({config.speech_pause_period} s)"
        )
    end_of_speech = config.end_of_speech or 0.0  # unset: end_of_speech_seconds keeps to these bounds
    if 0 < end_of_speech <= block:
        return (
            f"end_of_speech {config.end_of_speech} s is not longer than {one_block}: the gaps between "
            "blocks would be heard as the end of speech; 0 turns it off"
        )
    if end_of_speech >= config.speech_pause_period:
        return (
            f"end_of_speech {config.end_of_speech} s must be less than speech_pause_period "
            f"({config.speech_pause_period} s): 0 turns it off"
        )
    if 0 < config.partial_period < SHORTEST_PARTIAL_PERIOD:
        return (
            f"partial_period {config.partial_period} s is too short: 0 (partial results off) or from "
            f"{SHORTEST_PARTIAL_PERIOD} to 60 s"
        )
    if config.grammar and config.pocketsphinx_keywords:
        return "set grammar (pocketsphinx_grammar) or pocketsphinx_keywords, not both"
    if config.min_utterance_length > config.max_utterance_length:
        return (
            f"min_utterance_length {config.min_utterance_length} s is longer than max_utterance_length "
            f"{config.max_utterance_length} s: no utterance would ever be transcribed"
        )
    return None


_FORMAT = KeyValueFormat(
    SpeechEventConfig,
    {
        "language": KeyRule(choice("kinyarwanda", "english"), "kinyarwanda or english"),
        "verbose_mode": KeyRule(boolean, "true or false"),
        "rw_model_path": file_path("a path"),
        "en_model_path": file_path("a path"),
        "audio_storage_dir": file_path("a directory path, or nothing to store no audio"),
        "audio_storage_max_mb": KeyRule(number(float, 1.0, 10.0**7), "a number of MiB, 1 or more"),
        "cuda": KeyRule(boolean, "true or false"),
        "quantization": KeyRule(choice(*QUANTIZATIONS), " or ".join(QUANTIZATIONS)),
        "sample_rate": KeyRule(number(int, 8000, 192000), "an integer number of Hz from 8000 to 192000"),
        # Below 0.2 s the gaps inside speech end utterances: words come out cut into letters.
        "speech_pause_period": seconds(0.2, 60.0),
        "max_utterance_length": seconds(1.0, 300.0),
        "health_check_period": seconds(0.1, 3600.0),
        "publish_unrecognized": KeyRule(boolean, "true or false"),
        "max_message_length": seconds(0.1, 3600.0),
        "confidence": KeyRule(number(float, 0.0, 1.0), "a number from 0 to 1"),
        "heartbeat_msg_period": seconds(0.0, 3600.0),
        "grammar": file_path("a JSGF file or a file of phrases, one a line; empty: free speech"),
        "grammar_threshold": KeyRule(
            optional(number(float, -(10.0**6), 0.0)),
            "nats a phrase may be below the free decoding, 0 or less, or nothing for the engine's default",
        ),
        "pocketsphinx_keywords": file_path("a keyword list file (pocketsphinx kws format); empty: none"),
        "model": KeyRule(choice(*MODEL_FAMILIES), " or ".join(MODEL_FAMILIES)),
        "min_utterance_length": seconds(0.0, 300.0),
        "vad_threshold": KeyRule(number(float, 0.0, 1.0), "a speech probability from 0 to 1; 0: no check"),
        "max_backlog": seconds(1.0, 3600.0),
        "recognition_timeout": seconds(0.0, 3600.0),
        "speculative_recognition": KeyRule(boolean, "true or false"),
        "speculation_gap": KeyRule(
            optional(number(float, 0.05, 60.0)),
            "a number of seconds from 0.05 to 60, or nothing for 0.1 where the turn ends at the end "
            "of speech and 0.3 elsewhere",
        ),
        "early_pause": seconds(0.0, 60.0),
        "complete_answers": KeyRule(text, "complete answers separated by commas, such as yes,no,yego,oya"),
        "partial_period": seconds(0.0, 60.0),
        "text_style": KeyRule(choice(*TEXT_STYLES), " or ".join(TEXT_STYLES)),
        "turn_end_model": KeyRule(choice(*TURN_END_MODELS), "auto, none or smart-turn"),
        "turn_end_text": KeyRule(boolean, "true or false"),
        "end_of_speech": KeyRule(
            optional(number(float, 0.0, 60.0)),
            "a number of seconds from 0 (off) to 60, or nothing for 0.3 in grammar mode (Whisper, "
            "NeMo) and off elsewhere",
        ),
    },
    # The robot's v1.1 spellings.
    aliases={
        "interUtteranceLen": "speech_pause_period",
        "maxUtteranceLen": "max_utterance_length",
        "minUtteranceLen": "min_utterance_length",
        # The key's name before every engine took a grammar.
        "pocketsphinx_grammar": "grammar",
    },
    check=_together,
)
# The keys that name files (file_path above); a scenario takes relative ones from its own folder.
PATH_KEYS = _FORMAT.path_keys


def names_a_file(spelling: str) -> bool:
    """Whether a key as a file or a scenario may spell it (its camelCase, an alias such as
    pocketsphinx_grammar) names a file."""
    return _FORMAT.names_a_file(spelling)


def parse_config(content: str, source: str = "<config>") -> SpeechEventConfig:
    """Parse the text of a configuration file; ``source`` names it in a ConfigError."""
    return _FORMAT.parse(content, source)


def load_config(path: Union[str, Path]) -> SpeechEventConfig:
    """Read the configuration file at ``path``; ConfigError names the file, line, key and what is allowed."""
    return _FORMAT.load(path)


def apply_overrides(
    base: SpeechEventConfig, overrides: Mapping[str, object], source: str
) -> SpeechEventConfig:
    """``base`` with ``overrides`` (typed values, as a scenario's TOML gives them) checked and applied."""
    return _FORMAT.apply_overrides(base, overrides, source)


def format_config(config: SpeechEventConfig) -> str:
    """The text of a configuration file that ``parse_config`` reads back as ``config``."""
    return _FORMAT.format(config)
