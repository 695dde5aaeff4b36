#!/usr/bin/env bash
# The viewer in a real GLFW window: runs test_view_window's ViewWindow tests
# inside a virtual X display (Xvfb), where GLFW opens a 4.5 core window on
# Mesa's llvmpipe.
#
# usage: run_view_window_tests.sh TEST_BINARY
# Exits 77 (ctest: skipped) when xvfb-run is not installed; CI installs it
# (.ci/install-deps), so there the tests always run.
set -euo pipefail
binary=$1
if ! command -v xvfb-run > /dev/null 2>&1; then
  echo "SKIP: xvfb-run not found (Debian: apt-get install xvfb xauth)"
  exit 77
fi
exec xvfb-run -a -s "-screen 0 1920x1080x24" "$binary" --gtest_filter='ViewWindow.*'
