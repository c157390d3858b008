"""``speech_event_driver.py -c config/speech_event_driver.ini FILE.wav``: the driver as a ROS node."""

import argparse
import sys
import time
from typing import List, Optional

from harness.driver import DRIVER_FORMAT, WavError, play, read_wav
from speech_event import SIGNAL_TOPIC
from speech_event.application import without_remappings
from speech_event.keyvalue import ConfigError
from speech_event.messages import Float32MultiArray

SUBSCRIBER_TIMEOUT = 30.0


def main(argv: Optional[List[str]] = None) -> int:
    parser = argparse.ArgumentParser(prog="speech_event_driver")
    parser.add_argument("-c", "--config", required=True, help="driver configuration (Table 2 keys)")
    parser.add_argument("wav", help="the audio to publish, a PCM WAV file")
    arguments = parser.parse_args(without_remappings(argv))
    try:
        config = DRIVER_FORMAT.load(arguments.config)
        audio = read_wav(arguments.wav, config.sample_rate)
    except (ConfigError, WavError) as problem:
        print(f"error: {problem}", file=sys.stderr)
        return 2
    import rospy

    from speech_event.adapters.ros import RosClock, RosTransport

    rospy.init_node("soundDetection")
    publisher = RosTransport().advertise(SIGNAL_TOPIC, Float32MultiArray)
    deadline = time.monotonic() + SUBSCRIBER_TIMEOUT
    while publisher.connections() == 0 and time.monotonic() < deadline:  # earlier messages are lost
        time.sleep(0.01)
    clock = RosClock()
    end = play(audio, config, publisher, clock)
    while not rospy.is_shutdown() and clock.now() < end + 0.5:
        time.sleep(0.05)
    return 0
