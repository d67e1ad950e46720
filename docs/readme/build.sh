#!/usr/bin/env bash
# Rebuild README.md from docs/readme/: the two commands and command line (head.md), a compact
# case-file reference (reference.md) and the outputs with how to open them (outputs.md). The full
# texts live in docs/*.md, linked from the README; keep the README under ~400 lines.
set -euo pipefail
cd "$(dirname "$0")/../.."
{
  cat docs/readme/head.md
  echo
  cat docs/readme/reference.md
  echo
  cat docs/readme/outputs.md
} > README.md
wc -l README.md
