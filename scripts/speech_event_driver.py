#!/usr/bin/python3
# The driver: publishes a WAV file on /soundDetection/signal as soundDetection would (see harness/driver.py).
import sys

try:
    from harness.driver_node import main
except ModuleNotFoundError as missing:  # this Python lacks Speech Event or what it needs
    print(
        f"error: {sys.executable} cannot import {missing.name}: see README.md, 'On ROS and on the robot'",
        file=sys.stderr,
    )
    sys.exit(2)

sys.exit(main())
