#!/usr/bin/env bash
# The Python environment of the tests that read limb's files with the
# official readers (tests/python/.venv; pinned in requirements.txt).
# Idempotent; exits non-zero when the packages cannot be installed.
set -euo pipefail
cd "$(dirname "$0")"
if [ -x .venv/bin/python ] && .venv/bin/python -c 'import mcap' 2>/dev/null; then exit 0; fi
python3 -m venv .venv
.venv/bin/pip install -q --disable-pip-version-check -r requirements.txt
