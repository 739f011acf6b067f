#!/usr/bin/env bash
# Every measure of the object world model with the weights in W (default: the shipped ones),
# on the unseen seed data/objects-test (scripts/objects_data.sh makes it). Records in runs/eval/.
set -euo pipefail
cd "$(dirname "$0")/.."
A=${AFFORD:-.venv/bin/afford}
W=${1:-src/afford/weights/objects}
OUT=runs/eval
mkdir -p $OUT
$A eval objects --weights $W/perception.safetensors --data data/objects-test --split all \
    --out $OUT/perception.json --pictures docs/objects-perception.png
$A eval dynamics --weights $W/dynamics.safetensors --data data/objects-test --split all \
    --out $OUT/dynamics-true.json --pictures docs/objects-dynamics.png
$A eval dynamics --weights $W/dynamics.safetensors --data data/objects-test --split all \
    --perception $W/perception.safetensors --out $OUT/dynamics-perceived.json
# The simulator run from perceived and from true states: 300 sequences (it simulates every one)
$A eval dynamics --simulator --data data/objects-test --split all --limit 300 \
    --perception $W/perception.safetensors --out $OUT/simulator-perceived.json
$A eval dynamics --simulator --data data/objects-test --split all --limit 300 --out $OUT/simulator-true.json
$A eval dynamics --weights $W/dynamics.safetensors --data data/objects-test --split all --limit 300 \
    --perception $W/perception.safetensors --out $OUT/dynamics-perceived-300.json
