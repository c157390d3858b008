"""The robot's topic names, and the fixed texts the node publishes on its text topic."""

SIGNAL_TOPIC = "/soundDetection/signal"
TEXT_TOPIC = "/speechEvent/text"
SOUND_DETECTION_DOWN = "Error: soundDetection is down"
SPEECH_NOT_RECOGNIZED = "Error: speech not recognized"
