#!/usr/bin/python3
# The Speech Event node, as roslaunch and the seed's user manual run it. The interpreter is the
# system Python that has rospy; launch files may choose another with launch-prefix.
import sys

from speech_event.application import main

sys.exit(main())
