#!/usr/bin/env bash
# Creates plants/myoarm/.venv with the pinned packages of requirements.txt.
# Idempotent: does nothing when the venv already holds exactly those versions.
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
venv="$here/.venv"
req="$here/requirements.txt"
py="${PYTHON:-python3}"
stamp="$venv/.requirements.installed"
if [ -x "$venv/bin/python" ] && [ -f "$stamp" ] && cmp -s "$req" "$stamp" \
   && "$venv/bin/python" -c 'import mujoco, myo_sim, numpy' 2>/dev/null; then
  exit 0
fi
if [ ! -x "$venv/bin/python" ]; then
  "$py" -m venv "$venv" || { echo "setup.sh: python3 -m venv failed (install python3-venv?)" >&2; exit 1; }
fi
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check -r "$req" \
  || { echo "setup.sh: pip install failed" >&2; exit 1; }
"$venv/bin/python" -c 'import mujoco, myo_sim, numpy' \
  || { echo "setup.sh: import check failed" >&2; exit 1; }
cp "$req" "$stamp"
