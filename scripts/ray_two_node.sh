#!/usr/bin/env bash
# A campaign on a two-node Ray cluster started as a user would (issue 19, item 4), both nodes on this machine:
#   1. `ray start --head` and `ray start --address` (one CPU each);
#   2. the same campaign on the local backend (the reference) and on the cluster;
#   3. mid-campaign the worker node is killed (its raylet and workers: on one machine `ray stop --force` would
#      stop the head too); Ray re-runs its lost batches on the head, the campaign is resumed once more (a no-op
#      when nothing is missing) and the store must hold exactly N unique trials, record for record the local
#      backend's (timings aside).
# Usage: scripts/ray_two_node.sh [OUT_DIR] [N_TRIALS]     (from the repository root, after `make test`'s set-up)
#
# On real machines the same two commands, with the head's address (the head prints it):
#   head$    RAY_AUTH_MODE=token ray start --head --port=6379
#   worker$  RAY_AUTH_MODE=token ray start --address=HEAD_IP:6379      # copy ~/.ray/auth_token from the head first
#   head$    RAY_AUTH_MODE=token wrp-eval campaign CONFIG --backend ray   # campaign.backend.address: HEAD_IP:6379
# Ray >= 2.5x starts local clusters with token authentication (~/.ray/auth_token, written by the head): every
# other process that joins or connects needs RAY_AUTH_MODE=token and that token.
set -euo pipefail
BIN=${BIN:-.venv/bin}
OUT=${1:-logs/ray-two-node}
N=${2:-96}
PORT=${RAY_PORT:-6390}
export RAY_AUTH_MODE=token
mkdir -p "$OUT"
rm -rf "$OUT/local" "$OUT/ray"

cleanup() { "$BIN/ray" stop --force > /dev/null 2>&1 || true; }
trap cleanup EXIT
cleanup

"$BIN/ray" start --head --port="$PORT" --num-cpus=1 --include-dashboard=false --disable-usage-stats \
    > "$OUT/head.log" 2>&1
ADDRESS=$(grep -o "ray start --address='[^']*'" "$OUT/head.log" | head -1 | sed "s/.*'\(.*\)'/\1/")
echo "head at $ADDRESS"
"$BIN/ray" start --address="$ADDRESS" --num-cpus=1 --disable-usage-stats > "$OUT/worker.log" 2>&1
WORKER_RAYLET=$(pgrep -n -f "ray/raylet/raylet ")          # the newest raylet: the node that just joined
"$BIN/ray" status --address="$ADDRESS" | sed -n '/Active:/,/Pending:/p'

cat > "$OUT/config.yaml" <<EOF
run: {name: ray-two-node, seed: 0}
ship: {type: stylized}
wind: {source: synthetic, speed_10m_mps: 6.0, direction_deg: 270.0, turbulence: {severity: moderate}}
campaign:
  n_trials: $N
  batch_size: 4
  wind:
    speed_10m_m_s: {dist: uniform, low: 3.0, high: 8.0}
    direction_deg: {dist: normal, mean: 270.0, std: 30.0}
    turbulence: {severity: moderate}
  perturbation: {design: physical}
  oracle: synthetic
  backend: {kind: ray, address: "$ADDRESS", max_attempts: 2}
  outputs: {rerun: false}
EOF

echo "local backend (reference) ..."
"$BIN/wrp-eval" campaign "$OUT/config.yaml" --out "$OUT/local" --backend local > "$OUT/local.log" 2>&1

echo "two-node cluster ..."
"$BIN/wrp-eval" campaign "$OUT/config.yaml" --out "$OUT/ray" > "$OUT/ray.log" 2>&1 &
CAMPAIGN=$!
KILLED_AT=-1
# kill the worker node once a third of the trials are stored
while kill -0 "$CAMPAIGN" 2> /dev/null; do
    DONE=$("$BIN/python" -c "from wrp_eval.campaign.store import TrialStore; print(len(TrialStore('$OUT/ray').stored_ids()))" 2> /dev/null || echo 0)
    if [ "$DONE" -ge $((N / 3)) ]; then
        echo "killing the worker node (raylet $WORKER_RAYLET and its workers) at $DONE stored trials"
        pkill -9 -P "$WORKER_RAYLET" || true
        kill -9 "$WORKER_RAYLET" || true
        KILLED_AT=$DONE
        break
    fi
    sleep 1
done
wait "$CAMPAIGN" || echo "the campaign run ended with status $? (resumed below)"
"$BIN/ray" status --address="$ADDRESS" | sed -n '/Active:/,/Pending:/p' || true
echo "resume ..."
"$BIN/wrp-eval" campaign "$OUT/config.yaml" --out "$OUT/ray" >> "$OUT/ray.log" 2>&1

"$BIN/python" - "$OUT" "$N" "$KILLED_AT" <<'PY'
import json, sys
from wrp_eval.campaign.records import TIMING_COLUMNS
from wrp_eval.campaign.store import TrialStore
out, n, killed_at = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
def records(folder):
    table = TrialStore(folder).read_table()
    return table, json.dumps(table.drop_columns(list(TIMING_COLUMNS)).sort_by("trial_id").to_pylist(), sort_keys=True)
local, local_json = records(f"{out}/local")
ray, ray_json = records(f"{out}/ray")
ids = ray.column("trial_id").to_pylist()
workers = sorted(set(ray.column("worker").to_pylist()))
doc = {"trials": n, "worker_node_killed_at_trials": killed_at, "stored_on_ray": len(ids), "unique_on_ray": len(set(ids)),
       "same_records_as_local": local_json == ray_json, "ray_workers": workers}
print(json.dumps(doc, indent=1))
ok = doc["stored_on_ray"] == n and doc["unique_on_ray"] == n and doc["same_records_as_local"]
json.dump(doc, open(f"{out}/summary.json", "w"), indent=1)
sys.exit(0 if ok else 1)
PY
