#!/usr/bin/python3
# soundDetection stand-in that replays a scenario file (see harness/ros/stand_in.py).
import sys

try:
    from harness.ros.stand_in import main
except ModuleNotFoundError as missing:  # this Python lacks Speech Event or what it needs
    print(
        f"error: {sys.executable} cannot import {missing.name}: see README.md, 'On ROS and on the robot'",
        file=sys.stderr,
    )
    sys.exit(2)

sys.exit(main())
