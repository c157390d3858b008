#!/usr/bin/env bash
# Installs Debian's ROS 1 packages that the tox env "ros" needs, when they are missing.
# rospy is not on PyPI: ROS 1 comes from Debian and runs under /usr/bin/python3.
set -euo pipefail
packages=(ros-core python3-rospy python3-std-msgs python3-rosgraph-msgs python3-rostest)
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if ((${#missing[@]})); then
  echo "installing Debian's ROS packages: ${missing[*]}"
  run_as_root=()
  [ "$(id -u)" -eq 0 ] || run_as_root=(sudo)
  "${run_as_root[@]}" apt-get update -qq
  "${run_as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
fi
