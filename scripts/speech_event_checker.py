#!/usr/bin/python3
# The checker of the test-harness launch file (see harness/ros_checker.py).
import sys

from harness.ros_checker import main

sys.exit(main())
