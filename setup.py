"""For catkin only (catkin_python_setup needs a setup.py); pip reads pyproject.toml."""

from setuptools import setup

try:
    from catkin_pkg.python_setup import generate_distutils_setup
except ImportError:  # pip, outside a catkin workspace
    setup()
else:
    setup(
        **generate_distutils_setup(
            packages=[
                "speech_event",
                "speech_event.adapters",
                "speech_event.exporters",
                "speech_event.interfaces",
                "speech_event.pipeline",
                "speech_event.recognizers",
                "speech_event.recognizers.nemo",
                "speech_event.recognizers.onnx",
                "speech_event.recognizers.whisper",
                "harness",
                "harness.ros",
                "fixtures",
            ],
            package_data={
                "harness": ["data/*.txt"],
                "speech_event": [
                    "definitions/msg/*.msg",
                    "definitions/srv/*.srv",
                    "definitions/action/*.action",
                ],
            },
        )
    )
