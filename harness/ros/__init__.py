"""Scenario replay on a real roscore (needs rospy): the runner, the soundDetection stand-in, the
checker and the scenario node of the test-harness launch file. This package itself imports no ROS."""
