#!/usr/bin/python3
# The Speech Event node configured by a scenario file, for the test-harness launch file.
import sys

from harness.ros_scenario_node import main

sys.exit(main())
