#!/usr/bin/env bash
# Issue 30: ROS 2 bags as input. A synthetic sequence written as bags (MCAP with zstd / lz4
# chunks, SQLite; raw and compressed images; the pose only as a TF chain) gives the same
# scene through `semrec run` as the folder it was written from; `semrec info` lists the topics,
# the chosen ones and the TF chain; bad bags are clear errors.
set -u
SEMREC="$1"
MAKE_BAG="$2"
fail() { echo "FAIL: $*"; exit 1; }
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
"$SEMREC" synth --preset six-objects --frames 8 --out "$tmp/syn" >/dev/null || fail "synth failed"
# Depth as 32FC1 metres: exactly the folder's depth (synth stores 1/5000 m).
"$MAKE_BAG" "$tmp/syn" "$tmp/zstd" --float-depth || fail "writing the zstd bag failed"
"$MAKE_BAG" "$tmp/syn" "$tmp/lz4.mcap" --compression lz4 --bare --float-depth || fail "writing the lz4 bag failed"
"$MAKE_BAG" "$tmp/syn" "$tmp/sqlite" --storage sqlite3 --float-depth || fail "writing the SQLite bag failed"

"$SEMREC" info "$tmp/zstd" >"$tmp/info.txt" 2>&1 || fail "info on the bag failed: $(tail -3 "$tmp/info.txt")"
for want in "rosbag2 (mcap)" "/camera/color/image_raw" "sensor_msgs/msg/CameraInfo" \
  "TF map -> odom -> base_link -> camera_link -> camera_color_optical_frame" \
  "frames: 8 of 8 colour images paired" "zstd chunk"; do
  grep -qF "$want" "$tmp/info.txt" || { cat "$tmp/info.txt"; fail "info does not say '$want'"; }
done

# Labels for the bag's frames: the synthetic ground truth under the bag's frame names.
labels="$tmp/labels"; mkdir -p "$labels/semantic" "$labels/instance"
cp "$tmp/syn/gt/classes.json" "$labels/"
i=0
for f in $(ls "$tmp/syn/semantic" | sort); do
  name="$(printf 'frame-%06d.depth.png' "$i")"
  cp "$tmp/syn/semantic/$f" "$labels/semantic/$name"
  cp "$tmp/syn/instance/$f" "$labels/instance/$name"
  i=$((i + 1))
done

"$SEMREC" mesh "$tmp/syn" --labels gt --out "$tmp/folder_out" --no-ply >"$tmp/folder.log" 2>&1 ||
  fail "mesh on the folder failed: $(tail -3 "$tmp/folder.log")"
for bag in zstd lz4.mcap sqlite; do
  "$SEMREC" mesh "$tmp/$bag" --labels "$labels" --out "$tmp/out_$bag" --no-ply >"$tmp/$bag.log" 2>&1 ||
    fail "mesh on the $bag bag failed: $(tail -3 "$tmp/$bag.log")"
  python3 - "$tmp/folder_out/summary.json" "$tmp/out_$bag/summary.json" <<'PY' || fail "the $bag bag gives another scene"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
def objs(j):
    # The same depth, poses to 1e-9 and labels: the same fused points and meshes.
    return sorted((o["id"], o["class"], o["fused_points"], o["vertices"], o["triangles"])
                  for o in j["objects"])
oa, ob = objs(a), objs(b)
if oa != ob:
    print("folder:", oa); print("bag:   ", ob); sys.exit(1)
print(f"{len(oa)} objects alike")
PY
done

# Bad input: not a bag, a damaged one, a missing topic.
printf 'not a bag' >"$tmp/x.mcap"
"$SEMREC" info "$tmp/x.mcap" >"$tmp/bad.txt" 2>&1 && fail "info accepted a file that is not MCAP"
grep -q "x.mcap: not an MCAP file" "$tmp/bad.txt" || { cat "$tmp/bad.txt"; fail "unclear error for a non-MCAP file"; }
"$SEMREC" info "$tmp/zstd" --depth-topic /nope >"$tmp/bad.txt" 2>&1 && fail "info accepted a missing topic"
grep -q "no topic '/nope'" "$tmp/bad.txt" || { cat "$tmp/bad.txt"; fail "unclear error for a missing topic"; }
echo "bags: ok"
