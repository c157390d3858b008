#!/usr/bin/env bash
# Installs the Debian packages named as arguments when they are missing (root, or sudo).
# The tox envs call it: espeak-ng for the tts voice, ROS 1 for the env "ros" (rospy is not on
# PyPI: Debian's ROS runs under /usr/bin/python3).
set -euo pipefail
missing=()
for package in "$@"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if ((${#missing[@]})); then
  echo "installing Debian packages: ${missing[*]}"
  run_as_root=()
  [ "$(id -u)" -eq 0 ] || run_as_root=(sudo)
  "${run_as_root[@]}" apt-get update -qq
  "${run_as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
fi
