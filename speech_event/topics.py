"""The robot's topic names, and the fixed texts the node publishes on its text topic."""

SIGNAL_TOPIC = "/soundDetection/signal"
TEXT_TOPIC = "/speechEvent/text"
# The text of the utterance being spoken, so far (speech_event/turns/partials.py).
PARTIAL_TOPIC = "/speechEvent/partial"
# Every partial and final text with its confidence, language, engine and times (msg/Transcript.msg).
TRANSCRIPT_TOPIC = "/speechEvent/transcript"
SOUND_DETECTION_DOWN = "Error: soundDetection is down"
SPEECH_NOT_RECOGNIZED = "Error: speech not recognized"
