#!/usr/bin/env bash
# The main job of the README: installs what is missing, builds (Release), and runs the full system
# (IMM bank + shadow filter, ini/imm7-shadow.ini) on the built-in rendered scene; prints a summary
# (frames, fps, accuracy against the scene's ground truth). Outputs go to out-default/.
set -euo pipefail
cd "$(dirname "$0")/../.."
share/scripts/install-deps.sh
cmake -S . -B build -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)" --target imm-monoslam
build/bin/imm-monoslam ini/imm7-shadow.ini --out out-default "$@"
