#!/usr/bin/python3
# The checker of the test-harness launch file (see harness/ros/checker.py).
import sys

try:
    from harness.ros.checker import main
except ModuleNotFoundError as missing:  # this Python lacks Speech Event or what it needs
    print(
        f"error: {sys.executable} cannot import {missing.name}: see README.md, 'On ROS and on the robot'",
        file=sys.stderr,
    )
    sys.exit(2)

sys.exit(main())
