#!/usr/bin/python3
# The presentation window on ROS (see speech_event/gui.py): python3 -m speech_event.gui does the same.
import sys

try:
    from speech_event.gui import main
except ModuleNotFoundError as missing:  # this Python lacks Speech Event or what it needs
    print(
        f"error: {sys.executable} cannot import {missing.name}: see README.md, 'On ROS and on the robot'",
        file=sys.stderr,
    )
    sys.exit(2)

sys.exit(main())
