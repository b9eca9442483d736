#!/usr/bin/env bash
# Gradescope's setup.sh for bt_nav's lab autograder (docs/autograder.md): run once, as root, when Gradescope builds
# the autograder's image from the zip (`make autograder-zip`: this file, run_autograder, bt_nav's wheel, and your
# weights.yaml if you put one in autograder/).
#
# It installs Python (3.11 or newer: pick a base image that has it, e.g. Ubuntu 24.04), a virtual environment
# with bt_nav from the zip's wheel, its dependencies (matplotlib; ROS 2 Jazzy's rclpy and messages as pip wheels: no
# ROS install, no sourcing). Environment: BT_NAV_AUTOGRADER_SOURCE (the unzipped autograder, default
# /autograder/source), BT_NAV_AUTOGRADER_VENV (default /autograder/venv), BT_NAV_AUTOGRADER_APT (default 1; 0 skips
# apt-get). A wheels/ folder in the zip is searched first (for a machine that cannot reach the package index).
set -euo pipefail

SOURCE="${BT_NAV_AUTOGRADER_SOURCE:-/autograder/source}"
VENV="${BT_NAV_AUTOGRADER_VENV:-/autograder/venv}"

if [ "${BT_NAV_AUTOGRADER_APT:-1}" = 1 ]; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq python3 python3-venv python3-pip >/dev/null
fi
python3 -c 'import sys; sys.exit(sys.version_info < (3, 11))' || {
    echo "setup.sh: bt_nav needs Python 3.11 or newer, this image has $(python3 --version 2>&1);" \
         "choose a newer base image (Ubuntu 24.04 has 3.12)" >&2
    exit 1
}
shopt -s nullglob
wheels=("$SOURCE"/bt_nav-*.whl)
if [ "${#wheels[@]}" -ne 1 ]; then
    echo "setup.sh: expected one bt_nav-*.whl in $SOURCE (make wheel), found ${#wheels[@]}" >&2
    exit 1
fi
find_links=()
[ -d "$SOURCE/wheels" ] && find_links=(--find-links "$SOURCE/wheels")
python3 -m venv "$VENV"
"$VENV/bin/python" -m pip install --quiet --upgrade pip
"$VENV/bin/python" -m pip install --quiet "${find_links[@]}" "${wheels[0]}" \
    "ros-jazzy-rclpy[fastrtps]" ros-jazzy-common-interfaces
"$VENV/bin/bt-nav" grade --help >/dev/null
echo "setup.sh: bt_nav installed in $VENV ($("$VENV/bin/python" --version))"
