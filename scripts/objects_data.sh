#!/usr/bin/env bash
# The datasets of the object world model, each resumable (re-run to continue):
#   data/poses          poses only, the paper's uniform draws: what the dynamics learn from,
#                       with data/poses-102 and data/poses-103 (the same, two more seeds)
#   data/objects-test   an unseen seed with images and instance masks: every objects measure
#   data/objects-train  images and instance masks: what perception learns from
#   data/poses-effects  poses only, executions that seek side effects
# Times on 2 cores are in docs/objects.md.
set -euo pipefail
cd "$(dirname "$0")/.."
A=${AFFORD:-.venv/bin/afford}
$A generate --out data/poses --sequences 6000 --seed 100 --poses-only "$@"
$A generate --out data/objects-test --sequences 1000 --seed 200 --masks "$@"
$A generate --out data/objects-train --sequences 2000 --seed 201 --masks "$@"
$A generate --out data/poses-effects --sequences 1200 --seed 101 --poses-only --actions effects "$@"
$A generate --out data/poses-102 --sequences 6000 --seed 102 --poses-only "$@"
$A generate --out data/poses-103 --sequences 6000 --seed 103 --poses-only "$@"
