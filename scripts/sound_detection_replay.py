#!/usr/bin/python3
# soundDetection stand-in that replays a scenario file (see harness/ros_sound_detection.py).
import sys

from harness.ros_sound_detection import main

sys.exit(main())
