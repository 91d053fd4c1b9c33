#!/bin/sh
# clang-tidy (the repository's .clang-tidy, warnings as errors) on every translation unit of
# kernel/, geo/, config/ and worker/, or on the FILES given: check_tidy.py (beside this file)
# says how, and how units found clean are remembered. Usage: check_tidy.sh BUILD_DIR [FILES...].
exec python3 "$(dirname "$0")/check_tidy.py" "$@"
