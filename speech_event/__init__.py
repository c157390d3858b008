"""Speech Event: the speech-to-text node of the CSSR4Africa robot.

The node transcribes audio from ``/soundDetection/signal`` and publishes the text on
``/speechEvent/text``. Its core depends on numpy and three ports (``Transport``, ``Clock``,
``Recognizer``) so the same code runs on an in-memory bus with a fake clock, on a real roscore,
and on the robot.
"""

SIGNAL_TOPIC = "/soundDetection/signal"
TEXT_TOPIC = "/speechEvent/text"
SOUND_DETECTION_DOWN = "Error: soundDetection is down"
SPEECH_NOT_RECOGNIZED = "Error: speech not recognized"
