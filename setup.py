"""For catkin only (catkin_python_setup needs a setup.py); pip reads pyproject.toml."""

from setuptools import find_packages, setup

try:
    from catkin_pkg.python_setup import generate_distutils_setup
except ImportError:  # pip, outside a catkin workspace
    setup()
else:
    setup(
        **generate_distutils_setup(
            # The packages pip installs (pyproject.toml's include), found rather than listed, so a
            # new one cannot be left out; msg/ and srv/ are catkin's own, built into its devel space.
            packages=find_packages(
                include=["speech_event*", "harness*", "fixtures*"],
                exclude=["speech_event.msg*", "speech_event.srv*"],
            ),
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
