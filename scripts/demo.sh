#!/usr/bin/env bash
# The main job: builds the host tools and runs the simulated UR5 + tracker session.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
cmake --preset host >/dev/null
cmake --build --preset host --target hivecal_cli >/dev/null
exec build/host/apps/hivecal/hivecal demo "$@"
