"""``python -m speech_event -c CONFIG``: the node, as ``speech-event`` and
scripts/speech_event_application.py run it; what the ROS replay starts, so that it needs no
checkout (an installed package has no scripts/ folder)."""

import sys

from speech_event.application import main

sys.exit(main())
