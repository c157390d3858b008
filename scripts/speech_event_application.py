#!/usr/bin/python3
# The Speech Event node, as roslaunch and the seed's user manual run it. The interpreter is the
# system Python that has rospy; launch files may choose another with launch-prefix.
import sys

try:
    from speech_event.application import main
except ModuleNotFoundError as missing:  # this Python lacks Speech Event or what it needs
    print(
        f"error: {sys.executable} cannot import {missing.name}: see README.md, 'On ROS and on the robot'",
        file=sys.stderr,
    )
    sys.exit(2)

sys.exit(main())
