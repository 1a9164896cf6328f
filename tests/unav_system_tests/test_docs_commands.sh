#!/usr/bin/env bash
# Every command of the docs marked ```bash runnable runs and exits 0 (check_docs.py).
source "$(dirname "$0")/common.sh"
python3 "$(dirname "$0")/check_docs.py" "$ws"
