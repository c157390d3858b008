#!/usr/bin/python3
# The driver: publishes a WAV file on /soundDetection/signal as soundDetection would (see harness/driver.py).
import sys

from harness.driver_node import main

sys.exit(main())
