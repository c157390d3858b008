#!/usr/bin/env bash
# Installs the Debian packages that are missing (root, or sudo). Each argument is a package name or
# a list file (tests/debian/*.txt: a name a line, '#' comments). The tox envs call it with their
# lists; the README's commands with theirs. rospy is not on PyPI: Debian's ROS runs under
# /usr/bin/python3.
set -euo pipefail
packages=()
for argument in "$@"; do
  if [ -f "$argument" ]; then
    while read -r name _; do packages+=("$name"); done < <(sed -e 's/#.*//' -e '/^[[:space:]]*$/d' "$argument")
  else
    packages+=("$argument")
  fi
done
missing=()
for package in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$package" 2>/dev/null | grep -q "install ok installed" || missing+=("$package")
done
if ((${#missing[@]})); then
  echo "installing Debian packages: ${missing[*]}"
  run_as_root=()
  [ "$(id -u)" -eq 0 ] || run_as_root=(sudo)
  "${run_as_root[@]}" apt-get update -qq
  "${run_as_root[@]}" env DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
fi
