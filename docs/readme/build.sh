#!/usr/bin/env bash
# Rebuild README.md from docs/: head, case-file reference, outputs, then the library parts.
set -euo pipefail
cd "$(dirname "$0")/../.."
{
  cat docs/readme/head.md
  sed -e 's/^# Case files/## Case-file reference/' -e 's/^## /### /' docs/case-file.md | sed -e 's/^### Case-file reference/## Case-file reference/'
  echo
  cat docs/outputs.md
  for part in meshes fe reduction hbm verification study batch benchmarks dependencies; do
    if [ -f "docs/$part.md" ]; then echo; cat "docs/$part.md"; fi
  done
} > README.md
