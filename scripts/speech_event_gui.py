#!/usr/bin/python3
# The presentation window on ROS (see speech_event/gui.py): python3 -m speech_event.gui does the same.
import sys

from speech_event.gui import main

sys.exit(main())
