#!/usr/bin/env bash
# The mechanism study of docs/calibration.md: each candidate perception / walk mechanism
# gets its time scale (tick) fitted to the published proximity baselines (paper-sim
# targets, all four set-ups), then -- only then -- the controller-selection conditions
# are simulated on the fitted profile. Run from the repository root:
#   bash docs/calibration/mechanisms.sh [OUT]        (default OUT: out/mechanisms)
set -euo pipefail
out="${1:-out/mechanisms}"
mkdir -p "$out"
st=.venv/bin/swarmtag
common=(--baseline paper-sim --profile base --free "tick=0.008:0.15:log" --evaluations 10 --no-progress)

fit() {  # fit NAME SETTINGS...
    local name="$1"; shift
    "$st" calibrate "${common[@]}" "$@" --name "$name" \
        --out "$out/$name.toml" --report "$out/$name-fit.md" > "$out/$name-fit.txt"
    "$st" simulate --profile "$out/$name.toml" --runs 100 --resamples 2000 --no-progress \
        --condition proximity --condition urgency:alpha=0.7 --condition urgency:alpha=3.0 \
        --condition urgency:alpha=9.0 --json > "$out/$name-treatments.json"
}

avoid=(--set motion.avoid_taken_faces=true)
fit disc-1m        --set detection_radius=1.0 "${avoid[@]}"
fit disc-3.6m      --set detection_radius=3.6 "${avoid[@]}"
fit camera-1m      --set perception=split --set camera.range=1.0 --set camera.occlusion=carriers "${avoid[@]}"
fit camera-1.5m-memory-30s --set perception=split --set camera.range=1.5 \
    --set camera.occlusion=carriers --set camera.memory=30 "${avoid[@]}"
fit camera-3.6m    --set perception=split --set camera.range=3.6 --set camera.occlusion=carriers "${avoid[@]}"
fit camera-1m-tumble --set perception=split --set camera.range=1.0 \
    --set walk.turn_interval=0.5 "${avoid[@]}"
